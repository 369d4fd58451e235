#include "moslam/vocab/shipped_location.h"

#include <cstdlib>
#include <fstream>
#include <string>

#include <gtest/gtest.h>

namespace moslam::vocab {
namespace {

namespace fs = std::filesystem;

// A temporary tree: repo/data/vocab/moslam_orb.mvoc and repo/build/apps/moslam/moslam.
class ShippedLocation : public ::testing::Test {
 protected:
  void SetUp() override {
    std::string pattern = (fs::temp_directory_path() / "moslam_vocab_XXXXXX").string();
    ASSERT_NE(mkdtemp(pattern.data()), nullptr);
    root_ = pattern;
    fs::create_directories(root_ / "repo/data/vocab");
    fs::create_directories(root_ / "repo/build/apps/moslam");
    fs::create_directories(root_ / "elsewhere");
    std::ofstream(root_ / "repo" / kShippedVocabulary) << "x";
    std::ofstream(root_ / "repo/build/apps/moslam/moslam") << "x";
  }
  void TearDown() override { fs::remove_all(root_); }
  fs::path root_;
};

TEST_F(ShippedLocation, FoundFromTheWorkingFolderFirst) {
  EXPECT_EQ(FindShippedVocabulary(root_ / "repo", root_ / "repo/build/apps/moslam/moslam"),
            root_ / "repo" / kShippedVocabulary);
}

TEST_F(ShippedLocation, FoundAboveTheExecutableFromAnotherFolder) {
  const fs::path found =
      FindShippedVocabulary(root_ / "elsewhere", root_ / "repo/build/apps/moslam/moslam");
  ASSERT_FALSE(found.empty());
  EXPECT_TRUE(fs::equivalent(found, root_ / "repo" / kShippedVocabulary));
}

TEST_F(ShippedLocation, NothingWhereThereIsNone) {
  EXPECT_TRUE(FindShippedVocabulary(root_ / "elsewhere", root_ / "elsewhere/moslam").empty());
  EXPECT_TRUE(FindShippedVocabulary(root_ / "elsewhere", "").empty());
  // A folder of that name is not a vocabulary.
  fs::create_directories(root_ / "elsewhere" / kShippedVocabulary);
  EXPECT_TRUE(FindShippedVocabulary(root_ / "elsewhere", "").empty());
}

TEST_F(ShippedLocation, LooksAtMostFourFoldersAboveTheExecutable) {
  fs::create_directories(root_ / "repo/a/b/c/d/e");
  EXPECT_TRUE(FindShippedVocabulary(root_ / "elsewhere", root_ / "repo/a/b/c/d/e/moslam").empty());
  EXPECT_FALSE(FindShippedVocabulary(root_ / "elsewhere", root_ / "repo/a/b/c/d/moslam").empty());
  const auto candidates = ShippedVocabularyCandidates("/w", "/x/y/moslam");
  ASSERT_EQ(candidates.size(), 4u);  // /w, /x/y, /x and the root
  EXPECT_EQ(candidates[0], fs::path("/w") / kShippedVocabulary);
  EXPECT_EQ(candidates[1], fs::path("/x/y") / kShippedVocabulary);
}

TEST(CurrentExecutable, IsThisTest) {
  const fs::path exe = CurrentExecutable();
  ASSERT_FALSE(exe.empty());
  EXPECT_NE(exe.filename().string().find("shipped_location"), std::string::npos) << exe;
}

}  // namespace
}  // namespace moslam::vocab
