"""A module whose import raises."""
raise ImportError("this planner needs a package that is not installed")
