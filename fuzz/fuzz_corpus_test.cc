// Replays the fuzzers' seeds and every committed finding (fuzz/regressions/<target>/) through the
// harnesses in every build, so that a fixed finding stays fixed without clang or libFuzzer.
#include <filesystem>
#include <fstream>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "fuzz_targets.h"
#include "moslam/testing/shared_data.h"

namespace moslam::fuzz {
namespace {
namespace fs = std::filesystem;

std::string Slurp(const fs::path& path) {
  std::ifstream file(path, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(file)), std::istreambuf_iterator<char>());
}

std::vector<fs::path> FilesIn(const fs::path& dir) {
  std::vector<fs::path> files;
  if (!fs::is_directory(dir)) return files;
  for (const auto& entry : fs::directory_iterator(dir)) {
    if (entry.is_regular_file()) files.push_back(entry.path());
  }
  std::sort(files.begin(), files.end());
  return files;
}

class FuzzCorpus : public ::testing::TestWithParam<const char*> {
 protected:
  static void SetUpTestSuite() {
    seeds_ = std::make_unique<moslam::testing::TempDir>();
    ASSERT_GT(WriteSeeds(MOSLAM_SOURCE_DIR, seeds_->path()), 10);
  }
  static void TearDownTestSuite() { seeds_.reset(); }
  static inline std::unique_ptr<moslam::testing::TempDir> seeds_;
};

// Every seed is a valid input: the harness reaches the parser's accepting end, so the fuzzers
// start from inputs that go all the way through.
TEST_P(FuzzCorpus, SeedsAreAccepted) {
  const FuzzTarget& target = FindTarget(GetParam());
  const auto files = FilesIn(fs::path(seeds_->path()) / target.name);
  ASSERT_FALSE(files.empty()) << "no seeds for " << target.name;
  for (const fs::path& file : files) {
    std::string error;
    EXPECT_TRUE(RunOne(target, Slurp(file), &error))
        << target.name << ": seed " << file.filename() << ": " << error;
  }
}

// A finding ends in InputError (false) or is accepted (true); a crash, an abort or another
// exception type fails the test binary itself. Each finding file says which in its name:
// `*.accept` must be accepted, anything else refused.
TEST_P(FuzzCorpus, FindingsStayFixed) {
  const FuzzTarget& target = FindTarget(GetParam());
  for (const fs::path& file :
       FilesIn(fs::path(MOSLAM_SOURCE_DIR) / "fuzz" / "regressions" / target.name)) {
    bool accepted = false;
    EXPECT_NO_THROW(accepted = RunOne(target, Slurp(file))) << file;
    EXPECT_EQ(accepted, file.extension() == ".accept") << file;
  }
}

// Truncations of each seed at every 7th byte: what a cut-off download or a full disk leaves.
TEST_P(FuzzCorpus, TruncatedSeedsAreRefusedOrAccepted) {
  const FuzzTarget& target = FindTarget(GetParam());
  int refused = 0;
  for (const fs::path& file : FilesIn(fs::path(seeds_->path()) / target.name)) {
    const std::string bytes = Slurp(file);
    for (size_t n = 0; n < bytes.size(); n += 7) {
      EXPECT_NO_THROW(refused += RunOne(target, bytes.substr(0, n)) ? 0 : 1)
          << file << " cut at " << n;
    }
  }
  EXPECT_GT(refused, 0);  // an empty file at least is refused by every parser
}

INSTANTIATE_TEST_SUITE_P(Targets, FuzzCorpus,
                         ::testing::Values("settings", "tum_list", "kitti_calib", "kitti_times",
                                           "trajectory", "model_card", "vocabulary", "map"),
                         [](const auto& info) { return std::string(info.param); });

TEST(FuzzTargets, EveryTargetIsReplayed) {
  EXPECT_EQ(Targets().size(), 8u);  // a new harness needs its line in the instantiation above
}

}  // namespace
}  // namespace moslam::fuzz
