// Loop closing end to end on the synthetic loop_room preset (docs/SYNTH.md): an RGB-D camera
// walks a 1 m circle in a static office looking outwards and comes back to its first views after
// one lap. The same deterministic run with and without loop closing is scored against the exact
// ground truth, as RGB-D and as monocular. A vocabulary is trained here on the sequence's own
// frames (a small one, so the test needs no shipped vocabulary file).
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <memory>
#include <string>

#include <gtest/gtest.h>

#include "moslam/eval/trajectory_io.h"
#include "moslam/feature/orb_extractor.h"
#include "moslam/io/dataset.h"
#include "moslam/io/image.h"
#include "moslam/io/orbslam_settings.h"
#include "moslam/slam/run_dataset.h"
#include "moslam/synth/generator.h"
#include "moslam/testing/sanitizer.h"
#include "moslam/testing/shared_data.h"
#include "moslam/vocab/vocabulary.h"

namespace moslam::slam {
namespace {

// Position error of the last pose after aligning the first estimated pose onto the first ground
// truth pose: how far the camera believes it is from where it is after the whole walk.
double EndPointDrift(const std::string& groundtruth, const eval::Trajectory& estimate) {
  const eval::Trajectory gt = eval::ReadTrajectory(groundtruth);
  auto nearest = [&](double t) {
    size_t best = 0;
    for (size_t k = 1; k < gt.size(); ++k) {
      if (std::abs(gt.timestamps[k] - t) < std::abs(gt.timestamps[best] - t)) best = k;
    }
    return gt.poses[best];
  };
  const geometry::SE3 align =
      nearest(estimate.timestamps.front()) * estimate.poses.front().Inverse();
  const geometry::SE3 last = align * estimate.poses.back();
  return (last.translation() - nearest(estimate.timestamps.back()).translation()).norm();
}

// One loop_room sequence (seed 1, 600 frames) and its vocabulary for every test here.
// MOSLAM_LOOP_ROOM: an already generated loop_room folder (to rerun quickly while working).
class LoopRoom : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new testing::TempDir;
    const char* existing = std::getenv("MOSLAM_LOOP_ROOM");
    folder_ = new std::string(existing ? existing : dir_->path());
    if (!existing) {
      synth::GeneratorOptions generator;
      generator.preset = "loop_room";
      generator.seed = 1;
      generator.out = *folder_;
      generator.progress = false;
      synth::GenerateSequence(generator);
    }
    vocabulary_ = new std::shared_ptr<const vocab::Vocabulary>(TrainVocabulary(*folder_, 5));
  }
  static void TearDownTestSuite() {
    delete vocabulary_;
    delete folder_;
    delete dir_;
  }
  static std::function<void(SystemOptions*)> With(bool loop_closing, bool monocular) {
    return [loop_closing, monocular](SystemOptions* o) {
      o->vocabulary = *vocabulary_;
      o->loop_closing = loop_closing;
      if (monocular) o->sensor = io::SensorType::kMonocular;
    };
  }
  static DatasetRun Run(bool loop_closing, bool monocular) {
    return RunDataset(*folder_, *folder_ + "/settings.yaml", /*deterministic=*/true, 0, "",
                      With(loop_closing, monocular));
  }

  static testing::TempDir* dir_;
  static std::string* folder_;
  static std::shared_ptr<const vocab::Vocabulary>* vocabulary_;
};
testing::TempDir* LoopRoom::dir_ = nullptr;
std::string* LoopRoom::folder_ = nullptr;
std::shared_ptr<const vocab::Vocabulary>* LoopRoom::vocabulary_ = nullptr;

TEST_F(LoopRoom, RgbdClosesTheLoopAndCutsDrift) {
  const std::string folder = *folder_;
  const DatasetRun off = Run(false, false);
  const DatasetRun on = Run(true, false);
  const double drift_off = EndPointDrift(folder + "/groundtruth.txt", off.estimate);
  const double drift_on = EndPointDrift(folder + "/groundtruth.txt", on.estimate);
  std::printf(
      "loop_room seed 1, %zu frames: loop closing off: ATE RMSE %.4f m, end-point drift %.4f m; "
      "on: %d loops, ATE RMSE %.4f m, end-point drift %.4f m\n",
      on.reports.size(), off.ate_rmse, drift_off, on.summary.loops_closed, on.ate_rmse, drift_on);
  EXPECT_EQ(off.summary.loops_closed, 0);
  EXPECT_GE(on.summary.loops_closed, 1);
  EXPECT_EQ(on.frames_ok, static_cast<int>(on.reports.size()));
  // Each loop is a return: the current keyframe at least one 8 s lap after the loop keyframe.
  ASSERT_EQ(on.summary.loop_times.size(), static_cast<size_t>(on.summary.loops_closed));
  for (const auto& [time, loop_time] : on.summary.loop_times) EXPECT_GT(time, loop_time + 7.0);
  // The bound: after 2.5 laps (15.7 m) the uncorrected camera carries the whole accumulated
  // drift (measured 0.28 m end-point, 6.1 cm ATE on seed 1), while the closed loop ties the map
  // to its start and later laps track against it, leaving only the depth noise's sub-centimetre
  // local error (measured 0.57 cm end-point, 0.65 cm ATE). Five times is the bar; the
  // end-point drift clears it by a wide margin on the seeds measured (docs/EVALUATION.md), the
  // ATE (drift averaged over the whole walk, SE(3)-aligned) must at least halve.
  EXPECT_GT(drift_off, 5.0 * drift_on);
  EXPECT_LT(2.0 * on.ate_rmse, off.ate_rmse);
}

TEST_F(LoopRoom, MonocularClosesTheLoopWithSim3) {
  MOSLAM_SKIP_UNDER_SANITIZER("two 600-frame monocular runs, 570 s under ASan");
  // The same walk seen by the colour camera alone: the map has an arbitrary, drifting scale, the
  // loop is a Sim(3) (measured scale 1.054 at the loop, here and with a vocabulary trained on seed
  // 2, docs/EVALUATION.md) and the essential graph has 7 degrees of freedom per keyframe.
  const DatasetRun off = Run(false, true);
  const DatasetRun on = Run(true, true);
  std::printf(
      "loop_room seed 1 monocular: loop closing off: ATE RMSE (Sim3) %.4f m; on: %d loops, ATE "
      "RMSE (Sim3) %.4f m\n",
      off.ate_rmse, on.summary.loops_closed, on.ate_rmse);
  EXPECT_EQ(off.summary.loops_closed, 0);
  EXPECT_GE(on.summary.loops_closed, 1);
  // Sim(3)-aligned ATE spreads the drift over the walk (the alignment absorbs the mean scale);
  // measured 2.8x lower with loop closing on seed 1; the bound asks for half.
  EXPECT_LT(2.0 * on.ate_rmse, off.ate_rmse);
}

// A street of identical houses (synth preset street_repeat, docs/SYNTH.md) that never revisits a
// place: ORB-SLAM2's tests accept loops between look-alike houses there (the first after about
// 60 frames on seed 1), each a jump as long as the road between the two look-alikes, which wrecks
// the map (ATE 0.02 -> 16.5 m on these 100 frames). The verification must refuse
// them all, so that the run with loop closing on is the run with it off, pose for pose.
TEST(AliasingStreet, FalseLoopsAreRefusedAndTheMapIsUntouched) {
  MOSLAM_SKIP_UNDER_SANITIZER("two stereo runs of the street, 266 s under ASan");
  testing::TempDir dir;
  synth::GeneratorOptions generator;
  generator.preset = "street_repeat";
  generator.seed = 1;
  generator.frames = 100;
  generator.out = dir.path();
  generator.progress = false;
  synth::GenerateSequence(generator);
  auto run = [&](bool loop_closing, bool verify) {
    return RunDataset(dir.path(), dir.path() + "/settings.yaml", /*deterministic=*/true, 0, "",
                      [&](SystemOptions* o) {
                        o->vocabulary_path = "data/vocab/moslam_orb.mvoc";  // the shipped one
                        o->loop_closing = loop_closing;
                        o->loop_verification = verify;
                      });
  };
  const DatasetRun off = run(false, true);
  const DatasetRun unverified = run(true, false);
  const DatasetRun verified = run(true, true);
  std::printf(
      "street_repeat seed 1, 100 frames: loop closing off ATE %.4f m; ORB-SLAM2's tests only: %d "
      "loops, ATE %.4f m; verified: %d loops, %d refused, ATE %.4f m\n",
      off.ate_rmse, unverified.summary.loops_closed, unverified.ate_rmse,
      verified.summary.loops_closed, verified.summary.loops_rejected, verified.ate_rmse);
  // The sequence still aliases (else this test would prove nothing) ...
  EXPECT_GE(unverified.summary.loops_closed, 1);
  EXPECT_GT(unverified.ate_rmse, 5.0 * off.ate_rmse);
  // ... and the verification finds those loops and refuses every one.
  EXPECT_EQ(verified.summary.loops_closed, 0);
  EXPECT_GE(verified.summary.loops_rejected, 1);
  EXPECT_EQ(verified.ate_rmse, off.ate_rmse);
  ASSERT_EQ(verified.estimate.size(), off.estimate.size());
  for (size_t i = 0; i < off.estimate.size(); ++i) {
    EXPECT_EQ(verified.estimate.poses[i].translation(), off.estimate.poses[i].translation()) << i;
  }
}

}  // namespace
}  // namespace moslam::slam
