// base's words: the edit distance and the nearest word to a mistyping (the command line's
// "did you mean", and any list of names).

#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "overtake/base/text.hpp"

namespace overtake::base {
namespace {

TEST(EditDistance, CountsInsertionsDeletionsSubstitutionsAndSwaps) {
  EXPECT_EQ(edit_distance("", ""), 0u);
  EXPECT_EQ(edit_distance("bench", "bench"), 0u);
  EXPECT_EQ(edit_distance("", "hunt"), 4u);
  EXPECT_EQ(edit_distance("drive", "drie"), 1u);    // a deletion
  EXPECT_EQ(edit_distance("drive", "drivex"), 1u);  // an insertion
  EXPECT_EQ(edit_distance("drive", "drove"), 1u);   // a substitution
  EXPECT_EQ(edit_distance("drive", "drvie"), 1u);   // two neighbours swapped
  EXPECT_EQ(edit_distance("kitten", "sitting"), 3u);
  EXPECT_EQ(edit_distance("abc", "cba"), 2u);
}

TEST(NearestWord, NamesTheNearestWhenItIsAMistypingAndNothingElse) {
  const std::vector<std::string> words = {"drive", "bench", "calibrate", "compare", "cut"};
  EXPECT_EQ(nearest_word(words, "bnech"), "bench");
  EXPECT_EQ(nearest_word(words, "calibrat"), "calibrate");
  EXPECT_EQ(nearest_word(words, "cutt"), "cut");
  // A third of a long word may be wrong; two edits of any.
  EXPECT_EQ(nearest_word(words, "compaer"), "compare");
  EXPECT_FALSE(nearest_word(words, "xyzzyplugh").has_value());
  EXPECT_FALSE(nearest_word({}, "drive").has_value());
  // Ties go to the first of the list.
  EXPECT_EQ(nearest_word({"ab", "ba"}, "aa"), "ab");
}

}  // namespace
}  // namespace overtake::base
