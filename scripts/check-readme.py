#!/usr/bin/env python3
"""The README's commands, run as written (the docs.readme test).

Every command line of README.md's ```sh blocks (a line ending in a backslash goes on to the
next) runs with bash, in order, in one working folder of its own, with the build's folder
first on PATH (so `overtake` is the binary just built) and HOME a folder of fixtures. Those
fill in what a reader brings: their own planner program (./my_planner, and the course's
project in ~/CarND-Path-Planning-Project: build/path_planning reading ../data/highway_map.csv;
both the tests' example program), map files (my_track.csv, highway_map.csv: tracks
`overtake track` makes), a config (mine.json), two
benches to compare (before/, after/; old/ and new/, of a Python planner named mine and
mine-v2), a Python planner class (planner.py:Planner, with a speed keyword). The repository's folders the lines name (data/,
examples/, include/, build/release/) are links to the real ones.

A line must exit 0. A line still running after --budget seconds is stopped as a user would
stop it, with Ctrl-C (SIGINT to its process group), and must then exit 130, overtake's status
for "interrupted, what was done is kept": its flags were taken and its work began (or 0, when
it ended by itself just as the Ctrl-C came). A line that
cannot run this way carries `[not run: REASON]` in its comment in the README and is listed as
not run, never skipped silently; so is a line with a planner program (--planner-cmd) on a
machine that gives processes no network of their own, where the program would take the
host's port 4567. A line whose work a later line reads (a search whose best trial a drive
then takes) carries `[budget: N s ...]` and runs that long before it is stopped.

Usage: check-readme.py --source DIR --binary-dir DIR [--budget S] [--file README.md]
"""

import argparse
import os
import re
import shutil
import signal
import subprocess
import sys
import tempfile
import time

NOT_RUN = re.compile(r"\[not run: ([^\]]+)\]")
BUDGET = re.compile(r"\[budget: (\d+) s\b[^\]]*\]")

def command_lines(text):
    """(line number, command) of each command in the ```sh blocks, continuations joined."""
    out = []
    in_block = False
    pending = None
    for number, line in enumerate(text.splitlines(), start=1):
        stripped = line.strip()
        if stripped.startswith("```"):
            in_block = stripped == "```sh" if not in_block else False
            pending = None
            continue
        if not in_block:
            continue
        if pending is not None:
            pending = (pending[0], pending[1] + "\n" + line)
        elif stripped and not stripped.startswith("#"):
            pending = (number, line)
        else:
            continue
        if not line.rstrip().endswith("\\"):
            out.append(pending)
            pending = None
    return out


def run(cmd, cwd, env, timeout):
    """Runs `cmd` in its own process group; (exit status, output, stopped at the budget)."""
    p = subprocess.Popen(["bash", "-c", cmd], cwd=cwd, env=env, stdout=subprocess.PIPE,
                         stderr=subprocess.STDOUT, start_new_session=True)
    try:
        out, _ = p.communicate(timeout=timeout)
        return p.returncode, out.decode(errors="replace"), False
    except subprocess.TimeoutExpired:
        # Ctrl-C, as a user would: to the whole group (bash and what it started).
        os.killpg(p.pid, signal.SIGINT)
        try:
            out, _ = p.communicate(timeout=60)
        except subprocess.TimeoutExpired:
            os.killpg(p.pid, signal.SIGKILL)
            out, _ = p.communicate()
            return -9, out.decode(errors="replace") + "\n(did not stop within 60 s of Ctrl-C)", True
        # bash reports its child's status: 130 from overtake, or 128 + SIGINT when the
        # signal itself ended it.
        return p.returncode, out.decode(errors="replace"), True


def private_network():
    """Whether a process can have a network of its own here (as overtake gives each run of a
    planner program): else such a program would listen on the host's port 4567."""
    flags = ["--net"] if os.geteuid() == 0 else ["--user", "--map-root-user", "--net"]
    try:
        return subprocess.run(["unshare", *flags, "true"], capture_output=True).returncode == 0
    except OSError:
        return False


def fixtures(work, home, binary_dir, source, env):
    """What a reader brings, made in `work` and `home`."""
    overtake = os.path.join(binary_dir, "overtake")
    program = os.path.join(binary_dir, "tests", "overtake_example_program")
    if not os.access(program, os.X_OK):
        sys.exit("check-readme: " + program + " is missing (build the tests' example program)")
    for name in ("data", "examples", "include", "config"):
        os.symlink(os.path.join(source, name), os.path.join(work, name))
    os.makedirs(os.path.join(work, "build"))
    os.symlink(binary_dir, os.path.join(work, "build", "release"))
    # The course's project: build/path_planning reads ../data/highway_map.csv, as the
    # course's programs do; ./my_planner the built-in track.
    project = os.path.join(home, "CarND-Path-Planning-Project")
    os.makedirs(os.path.join(project, "build"))
    os.makedirs(os.path.join(project, "data"))
    shutil.copy(os.path.join(source, "data", "tracks", "default.csv"),
                os.path.join(project, "data", "highway_map.csv"))
    for path, map_file in ((os.path.join(project, "build", "path_planning"),
                            "../data/highway_map.csv"),
                           (os.path.join(work, "my_planner"), "data/tracks/default.csv"),
                           (os.path.join(work, "planner"), "data/tracks/default.csv"),
                           (os.path.join(work, "path_planning"), "data/tracks/default.csv")):
        with open(path, "w") as f:
            f.write("#!/bin/sh\nexec " + program + " " + map_file + ' "$@"\n')
        os.chmod(path, 0o755)
    # A Python planner of the reader's, as a class with a keyword (planner.py:Planner): the
    # tests' example planner with its speed as a keyword.
    os.symlink(os.path.join(source, "tests", "python", "planners", "keyword_speed.py"),
               os.path.join(work, "planner.py"))
    with open(os.path.join(work, "mine.json"), "w") as f:
        f.write('{"planner": {"reference": {"assertiveness": 0.25}}}\n')
    steps = [
        [overtake, "track", "--seed", "11", "-o", "my_track.csv"],
        [overtake, "track", "--seed", "12", "-o", "highway_map.csv"],
        [overtake, "bench", "--quiet", "--seeds", "1-8", "--minutes", "1", "--out", "before"],
        [overtake, "bench", "--quiet", "--seeds", "1-8", "--minutes", "1", "--config",
         "mine.json", "--out", "after"],
        # Two benches of the reader's planner, before and after a change of its name.
        [overtake, "bench", "--quiet", "--policies", "mine", "--policy-py",
         "mine=examples/python/planner.py:plan", "--seeds", "1-8", "--minutes", "1", "--out",
         "old"],
        [overtake, "bench", "--quiet", "--policies", "mine-v2", "--policy-py",
         "mine-v2=examples/python/planner.py:plan", "--seeds", "1-8", "--minutes", "1", "--out",
         "new"],
    ]
    for step in steps:
        r = subprocess.run(step, cwd=work, env=env, capture_output=True, text=True)
        if r.returncode != 0:
            sys.exit("check-readme: the fixture `" + " ".join(step[1:]) + "` failed:\n" +
                     r.stdout + r.stderr)


def main():
    ap = argparse.ArgumentParser(description="Runs the README's commands as written.")
    ap.add_argument("--source", required=True, help="the repository")
    ap.add_argument("--binary-dir", required=True, help="the build folder (overtake in it)")
    ap.add_argument("--file", default="README.md", help="the Markdown file, in --source")
    ap.add_argument("--budget", type=float, default=10.0,
                    help="seconds a line runs before Ctrl-C stops it (default 10)")
    a = ap.parse_args()
    source = os.path.abspath(a.source)
    binary_dir = os.path.abspath(a.binary_dir)
    with open(os.path.join(source, a.file)) as f:
        lines = command_lines(f.read())
    if not lines:
        sys.exit("check-readme: no ```sh command lines in " + a.file)

    root = tempfile.mkdtemp(prefix="overtake-readme-")
    try:
        work = os.path.join(root, "work")
        home = os.path.join(root, "home")
        os.makedirs(work)
        os.makedirs(home)
        env = dict(os.environ)
        env["PATH"] = binary_dir + os.pathsep + env.get("PATH", "")
        env["HOME"] = home
        env.pop("PYTHONPATH", None)
        fixtures(work, home, binary_dir, source, env)
        failures = []
        counts = {"ran": 0, "stopped": 0, "not run": 0}
        isolated = private_network()
        for number, cmd in lines:
            where = a.file + ":" + str(number)
            first = cmd.splitlines()[0].strip()
            m = NOT_RUN.search(cmd)
            if m:
                counts["not run"] += 1
                print("not run  " + where + "  " + first + "\n         (" + m.group(1) + ")")
                continue
            if "--planner-cmd" in cmd and not isolated:
                counts["not run"] += 1
                print("not run  " + where + "  " + first + "\n         (no network namespace "
                      "on this machine: the program would listen on the host's port 4567)")
                continue
            started = time.monotonic()
            longer = BUDGET.search(cmd)
            budget = float(longer.group(1)) if longer else a.budget
            status, out, stopped = run(cmd, work, env, budget)
            took = time.monotonic() - started
            # A line that ends by itself just as the budget runs out has exited 0 before
            # the Ctrl-C reached it: as good as one that ended earlier.
            ok = status in (0, 130, -signal.SIGINT, 128 + signal.SIGINT) if stopped else status == 0
            tag = ("stopped " if stopped else "ran     ") if ok else "FAILED  "
            if ok:
                counts["stopped" if stopped else "ran"] += 1
            print(f"{tag} {where}  {first}  ({took:.1f} s, exit {status})")
            if not ok:
                failures.append((where, cmd, status, out))
        print(f"\n{counts['ran']} ran to the end, {counts['stopped']} stopped by Ctrl-C after "
              f"{a.budget:g} s as the budget, {counts['not run']} marked [not run], "
              f"{len(failures)} failed")
        for where, cmd, status, out in failures:
            tail = "\n".join(out.splitlines()[-15:])
            print(f"\n--- {where} (exit {status}):\n{cmd}\n{tail}")
        return 1 if failures else 0
    finally:
        shutil.rmtree(root, ignore_errors=True)


if __name__ == "__main__":
    sys.exit(main())
