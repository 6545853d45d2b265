#include "geometry/ascii_text.h"

#include <gtest/gtest.h>

#include <string>
#include <vector>

namespace vox {
namespace {

TEST(AsciiText, WordsJoinedAsASentenceListsThem) {
  EXPECT_EQ(joinedWords(std::vector<std::string>{}), "");
  EXPECT_EQ(joinedWords(std::vector<std::string>{"flexion"}), "flexion");
  EXPECT_EQ(joinedWords(std::vector<std::string>{"flexion", "abduction"}), "flexion and abduction");
  EXPECT_EQ(joinedWords(std::vector<std::string>{"flexion", "abduction", "rotation"}), "flexion, abduction and rotation");
}

TEST(AsciiText, CaseAndSuffixes) {
  EXPECT_EQ(toLowerAscii("AbC-9"), "abc-9");
  EXPECT_TRUE(endsWithIgnoringCase("phantom.NII.GZ", ".nii.gz"));
  EXPECT_FALSE(endsWithIgnoringCase("gz", ".nii.gz"));
  EXPECT_EQ(lowerExtension("dir.v2/mesh.VTU"), ".vtu");
  EXPECT_EQ(lowerExtension("dir.v2/mesh"), "");
}

}  // namespace
}  // namespace vox
