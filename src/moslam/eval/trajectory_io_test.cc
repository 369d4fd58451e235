#include "moslam/eval/trajectory_io.h"

#include <string>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "moslam/eval/test_trajectories.h"
#include "moslam/testing/shared_data.h"
#include "moslam/util/error.h"

namespace moslam::eval {
namespace {

using moslam::testing::TempDir;
using ::testing::HasSubstr;

// The InputError message of reading `contents` as `format`, or "" when it reads.
std::string ReadError(const std::string& contents, TrajectoryFormat format,
                      const std::string& name = "bad.txt") {
  TempDir dir;
  const std::string path = dir.Write(name, contents);
  try {
    ReadTrajectory(path, format);
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

void ExpectSamePoses(const Trajectory& a, const Trajectory& b, double rotation_tolerance) {
  ASSERT_EQ(a.size(), b.size());
  for (size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a.Position(i), b.Position(i)) << i;
    EXPECT_LT(a.poses[i].rotation().angularDistance(b.poses[i].rotation()), rotation_tolerance);
  }
}

TEST(TrajectoryIo, TumRoundTrip) {
  TempDir dir;
  const Trajectory t = testing::MakeCurve(50);
  const std::string path = dir.path() + "/t.txt";
  WriteTum(t, path);
  const Trajectory r = ReadTum(path);
  EXPECT_EQ(r.timestamps, t.timestamps);
  EXPECT_TRUE(r.raw_rotations.empty());
  ExpectSamePoses(r, t, 1e-14);
  EXPECT_EQ(DetectTrajectoryFormat(path), TrajectoryFormat::kTum);
}

TEST(TrajectoryIo, KittiRoundTripKeepsRawRotations) {
  TempDir dir;
  Trajectory t = testing::MakeCurve(20);
  t.timestamps.clear();
  const std::string path = dir.path() + "/poses.txt";
  WriteKitti(t, path);
  const Trajectory r = ReadKitti(path);
  EXPECT_FALSE(r.has_timestamps());
  ASSERT_EQ(r.raw_rotations.size(), 20u);
  for (size_t i = 0; i < r.size(); ++i) EXPECT_EQ(r.Matrix(i), t.Matrix(i)) << i;
  ExpectSamePoses(r, t, 1e-14);
  EXPECT_EQ(DetectTrajectoryFormat(path), TrajectoryFormat::kKitti);
  // Written again, the raw matrices come back bit for bit.
  WriteKitti(r, path);
  const Trajectory again = ReadKitti(path);
  for (size_t i = 0; i < r.size(); ++i) EXPECT_EQ(again.raw_rotations[i], r.raw_rotations[i]);
}

TEST(TrajectoryIo, KittiRotationsAreReorthonormalized) {
  TempDir dir;
  const std::string path = dir.Write("k.txt", "1.0001 0 0 1  0 1 0 2  0 0 0.9999 3\n");
  const Trajectory t = ReadKitti(path);
  const Eigen::Matrix3d R = t.poses[0].rotation_matrix();
  EXPECT_LT((R.transpose() * R - Eigen::Matrix3d::Identity()).norm(), 1e-12);
  EXPECT_EQ(t.raw_rotations[0](0, 0), 1.0001);  // as read
  EXPECT_EQ(t.Position(0), Eigen::Vector3d(1, 2, 3));
}

TEST(TrajectoryIo, EurocQuaternionIsWFirstAndStampsNanoseconds) {
  TempDir dir;
  const std::string path =
      dir.Write("data.csv",
                "#timestamp,p_RS_R_x [m],p_RS_R_y [m],p_RS_R_z [m],q_RS_w [],q_RS_x [],q_RS_y [],"
                "q_RS_z [],v_RS_R_x [m s^-1]\n"
                "1403636579758555392,4.688,-1.786,0.783,0.534,-0.153,-0.827,-0.082,0.1\n"
                "1403636579763555584,4.688,-1.786,0.787,0.534,-0.153,-0.827,-0.083,0.1\n");
  EXPECT_EQ(DetectTrajectoryFormat(path), TrajectoryFormat::kEuroc);
  const Trajectory t = ReadTrajectory(path);
  ASSERT_EQ(t.size(), 2u);
  EXPECT_DOUBLE_EQ(t.timestamps[0], 1403636579758555392.0 / 1e9);
  const Eigen::Quaterniond q = t.poses[0].rotation();
  const Eigen::Quaterniond expected =
      Eigen::Quaterniond(0.534, -0.153, -0.827, -0.082).normalized();
  EXPECT_LT(q.angularDistance(expected), 1e-12);
  // EuRoC written back (w first, nanoseconds) reads back to the same poses.
  const std::string out = dir.path() + "/out.csv";
  WriteEuroc(t, out);
  const Trajectory r = ReadEuroc(out);
  EXPECT_NEAR(r.timestamps[1], t.timestamps[1], 1e-6);
  ExpectSamePoses(r, t, 1e-14);
}

TEST(TrajectoryIo, CommentsBlankLinesAndCommasInTum) {
  TempDir dir;
  const std::string path =
      dir.Write("t.txt", "# ground truth\n\n1.0 1 2 3 0 0 0 1\n  \n2.0,1,2,3,0,0,0,1\n# end\n");
  const Trajectory t = ReadTrajectory(path, TrajectoryFormat::kTum);
  ASSERT_EQ(t.size(), 2u);
  EXPECT_EQ(t.timestamps[1], 2.0);
}

TEST(TrajectoryIo, NanLinesAndZeroQuaternionsAreSkippedAsTumDoes) {
  TempDir dir;
  const std::string path = dir.Write("t.txt",
                                     "1.0 0 0 0 0 0 0 1\n"
                                     "2.0 nan 0 0 0 0 0 1\n"
                                     "3.0 0 0 0 0 0 0 0\n"
                                     "4.0 1 0 0 0 0 0 1\n");
  const Trajectory t = ReadTum(path);
  ASSERT_EQ(t.size(), 2u);
  EXPECT_EQ(t.timestamps[1], 4.0);
}

TEST(TrajectoryIo, RepeatedTimestampIsKept) {
  TempDir dir;
  const std::string path =
      dir.Write("t.txt", "1.0 0 0 0 0 0 0 1\n1.0 1 0 0 0 0 0 1\n2.0 0 0 0 0 0 0 1\n");
  EXPECT_EQ(ReadTum(path).size(), 3u);
}

TEST(TrajectoryIo, BadFilesNameFileAndLine) {
  EXPECT_THAT(ReadError("1 0 0 0 0 0 0 1\n1 2 3\n", TrajectoryFormat::kTum),
              HasSubstr("bad.txt:2: expected 8 fields"));
  EXPECT_THAT(ReadError("# c\n1 0 0 0 0 0 x 1\n", TrajectoryFormat::kTum),
              HasSubstr("bad.txt:2: field 7 ('x') is not a number"));
  EXPECT_THAT(ReadError("2 0 0 0 0 0 0 1\n1 0 0 0 0 0 0 1\n", TrajectoryFormat::kTum),
              HasSubstr("bad.txt:2: timestamp 1.000000 is earlier than 2.000000 on line 1"));
  EXPECT_THAT(ReadError("1 0 0 0 1e-9 0 0 0\n", TrajectoryFormat::kTum),
              HasSubstr("bad.txt:1: invalid pose"));
  EXPECT_THAT(ReadError("1 0 0 0 0 1 0 0 0 0 1 0\n1 0 0\n", TrajectoryFormat::kKitti),
              HasSubstr("bad.txt:2: expected 12 fields"));
  EXPECT_THAT(ReadError("1 0 0 0 0 1 0 0 0 0 -1 0\n", TrajectoryFormat::kKitti),
              HasSubstr("bad.txt:1: the 3x3 block is not a rotation"));
  EXPECT_THAT(ReadError("1 0 0 nan 0 1 0 0 0 0 1 0\n", TrajectoryFormat::kKitti),
              HasSubstr("bad.txt:1: field 4 is not finite"));
  EXPECT_THAT(ReadError("1,2,3\n", TrajectoryFormat::kEuroc),
              HasSubstr("bad.txt:1: expected at least 8"));
  EXPECT_THAT(ReadError("# x\n1 2 3 4 5\n", TrajectoryFormat::kAuto),
              HasSubstr("bad.txt:2: cannot tell the trajectory format from 5 fields"));
  EXPECT_THAT(ReadError("", TrajectoryFormat::kAuto), HasSubstr("bad.txt: has no data lines"));
  EXPECT_THAT(ReadError("x", TrajectoryFormat::kTum, "missing/../none.txt"), HasSubstr("none.txt"));
}

// Issue 31: a position of -1e300 overflowed the alignment, which then blamed the geometry.
TEST(TrajectoryIo, PositionsBeyondAMillionKilometresAreNamed) {
  EXPECT_THAT(ReadError("1 0 0 0 0 0 0 1\n2 0 0 -1e300 0 0 0 1\n", TrajectoryFormat::kTum),
              HasSubstr("bad.txt:2: position (0, 0, -1e+300) lies beyond 1e+09 m"));
  EXPECT_THAT(ReadError("1 0 0 2e10 0 1 0 0 0 0 1 0\n", TrajectoryFormat::kKitti),
              HasSubstr("bad.txt:1: position"));
  EXPECT_EQ(ReadError("1 9e8 0 0 0 0 0 1\n", TrajectoryFormat::kTum), "");
}

TEST(TrajectoryIo, MissingFileIsAnInputError) {
  EXPECT_THROW(ReadTrajectory("/nonexistent/trajectory.txt"), InputError);
}

TEST(TrajectoryIo, TimesAttachAndMismatchIsNamed) {
  TempDir dir;
  Trajectory t = testing::MakeCurve(3);
  t.timestamps.clear();
  AttachTimes(dir.Write("times.txt", "0.0\n0.1\n0.2\n"), &t);
  EXPECT_EQ(t.timestamps[2], 0.2);
  const std::string short_times = dir.Write("short.txt", "0.0\n0.1\n");
  try {
    AttachTimes(short_times, &t);
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr("short.txt: has 2 timestamps but 'curve' has 3 poses"));
  }
  EXPECT_THROW(ReadTimes(dir.Write("bad.txt", "0.0\n0.1 2\n")), InputError);
  EXPECT_THROW(ReadTimes(dir.Write("dec.txt", "0.2\n0.1\n")), InputError);
}

TEST(TrajectoryIo, FormatNamesParse) {
  EXPECT_EQ(ParseTrajectoryFormat("KITTI"), TrajectoryFormat::kKitti);
  EXPECT_STREQ(TrajectoryFormatName(TrajectoryFormat::kEuroc), "euroc");
  EXPECT_THROW(ParseTrajectoryFormat("bag"), InputError);
}

TEST(TrajectoryIo, WritingStampedFormatsNeedsStamps) {
  TempDir dir;
  Trajectory t = testing::MakeCurve(2);
  t.timestamps.clear();
  EXPECT_THROW(WriteTum(t, dir.path() + "/x.txt"), InputError);
}

TEST(TrajectoryIo, SharedFilesAreDetected) {
  MOSLAM_SHARED_OR_SKIP(dir, "data/trajectories");
  EXPECT_EQ(DetectTrajectoryFormat(dir + "/fr2_desk_groundtruth.txt"), TrajectoryFormat::kTum);
  EXPECT_EQ(DetectTrajectoryFormat(dir + "/KITTI_00_gt.txt"), TrajectoryFormat::kKitti);
  EXPECT_EQ(ReadTrajectory(dir + "/fr2_desk_groundtruth.txt").size(), 20957u);
}

}  // namespace
}  // namespace moslam::eval
