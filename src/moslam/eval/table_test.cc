#include "moslam/eval/table.h"

#include <cmath>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "moslam/eval/test_trajectories.h"
#include "moslam/eval/trajectory_io.h"
#include "moslam/testing/error_of.h"
#include "moslam/testing/shared_data.h"
#include "moslam/util/error.h"

namespace moslam::eval {
namespace {

using moslam::testing::ErrorOf;
using moslam::testing::TempDir;
using ::testing::AllOf;
using ::testing::HasSubstr;

TEST(Table, ImprovementFormula) {
  EXPECT_DOUBLE_EQ(Improvement(0.2, 0.1), 50.0);
  EXPECT_DOUBLE_EQ(Improvement(0.1, 0.2), -100.0);
  EXPECT_DOUBLE_EQ(Improvement(0.8, 0.02), 97.5);
  EXPECT_TRUE(std::isnan(Improvement(0.0, 0.1)));
}

TEST(Table, RunSpecs) {
  const TableRun r = ParseRunSpec("fr3_walking_xyz:Ours:gt.txt:est.txt");
  EXPECT_EQ(r.sequence, "fr3_walking_xyz");
  EXPECT_EQ(r.method, "Ours");
  EXPECT_EQ(r.gt_path, "gt.txt");
  EXPECT_EQ(r.est_path, "est.txt");
  EXPECT_EQ(ParseRunSpec("00:ORB:gt.txt:est.txt:times.txt").gt_times, "times.txt");
  EXPECT_THROW(ParseRunSpec("seq:method:gt.txt"), InputError);
  EXPECT_THROW(ParseRunSpec("seq::gt.txt:est.txt"), InputError);
}

TEST(Table, ManifestWithHeaderAndBadLineNamed) {
  TempDir dir;
  const std::string g = dir.Write("g.txt", "");
  const std::string e = dir.Write("e.txt", "");
  const std::string o = dir.Write("o.txt", "");
  const auto runs = ReadRunManifest(dir.Write(
      "runs.csv",
      fmt::format("sequence,method,gt,est\n# comment\ns1,ORB-SLAM2,{},{}\ns1,Ours,{},{}\n", g, e, g,
                  o)));
  ASSERT_EQ(runs.size(), 2u);
  EXPECT_EQ(runs[1].est_path, o);
  try {
    ReadRunManifest(dir.Write("bad.csv", fmt::format("s1,ORB,{},{}\ns2,ORB\n", g, e)));
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr("bad.csv:2:"));
  }
}

// Issue 31: a quoted field with a comma shifted the row, and the error named only "a", the
// field taken for the ground truth; the manifest's line is named now.
TEST(Table, ManifestRowWhosePathsAreNoFilesIsNamedByLine) {
  TempDir dir;
  const std::string g = dir.Write("g.txt", "");
  const std::string e = dir.Write("e.txt", "");
  const std::string quoted = dir.Write("q.csv", fmt::format("\"s1,a\",ORB,{},{}\n", g, e));
  EXPECT_THAT(ErrorOf([&] { ReadRunManifest(quoted); }),
              AllOf(HasSubstr(quoted + ":1:"), HasSubstr("not an existing file")));
  const std::string twice =
      dir.Write("t.csv", fmt::format("s,a,{0},{1}\ns,b,{0},{1}\ns,a,{0},{1}\n", g, e));
  EXPECT_THAT(ErrorOf([&] { ReadRunManifest(twice); }),
              AllOf(HasSubstr(twice + ":3: a second run of method 'a'"), HasSubstr("line 1")));
  const std::string missing = dir.Write("m.csv", fmt::format("s1,ORB,{},none.txt\n", g));
  EXPECT_THAT(ErrorOf([&] { ReadRunManifest(missing); }),
              AllOf(HasSubstr(missing + ":1:"), HasSubstr("est 'none.txt'")));
}

ErrorStatistics Stats(double rmse, double mean, double median, double std) {
  ErrorStatistics s;
  s.count = 10;
  s.rmse = rmse;
  s.mean = mean;
  s.median = median;
  s.std = std;
  return s;
}

// One metric, two sequences, baseline and one variant; the variant misses sequence s2.
ResultTable SmallTable() {
  ResultTable t;
  t.metrics = {"ATE [m]"};
  t.sequences = {"fr3_w_xyz", "s2"};
  t.methods = {"ORB-SLAM2", "Ours"};
  t.cells = {{{Stats(0.4, 0.2, 0.1, 0.08), Stats(0.1, 0.1, 0.05, 0.02)},
              {Stats(1.0, 1.0, 1.0, 1.0), std::nullopt}}};
  return t;
}

TEST(Table, Markdown) {
  const std::string md = FormatTable(SmallTable(), TableFormat::kMarkdown, 4);
  EXPECT_THAT(md, HasSubstr("**ATE [m]**"));
  EXPECT_THAT(md, HasSubstr("| Sequence | ORB-SLAM2 RMSE | ORB-SLAM2 Mean | ORB-SLAM2 Median | "
                            "ORB-SLAM2 SD | Ours RMSE |"));
  EXPECT_THAT(md, HasSubstr("| F Ours RMSE (%) | F Ours Mean (%) |"));
  EXPECT_THAT(md, HasSubstr("|---|---:|"));
  EXPECT_THAT(md, HasSubstr("| fr3_w_xyz | 0.4000 | 0.2000 | 0.1000 | 0.0800 | 0.1000 | 0.1000 | "
                            "0.0500 | 0.0200 | 75.00 | 50.00 | 50.00 | 75.00 |"));
  EXPECT_THAT(md, HasSubstr("| s2 | 1.0000 | 1.0000 | 1.0000 | 1.0000 | – | – | – | – | – |"));
}

TEST(Table, Latex) {
  const std::string tex = FormatTable(SmallTable(), TableFormat::kLatex, 3);
  EXPECT_THAT(tex, HasSubstr("\\begin{tabular}{l|cccc|cccc|cccc}"));
  EXPECT_THAT(tex, HasSubstr("\\caption{ATE [m]}"));
  EXPECT_THAT(tex, HasSubstr("& \\multicolumn{4}{c|}{ORB-SLAM2} & \\multicolumn{4}{c|}{Ours} & "
                             "\\multicolumn{4}{c}{Improvement Ours (\\%)} \\\\"));
  EXPECT_THAT(tex, HasSubstr("Sequence & RMSE & Mean & Median & S.D. &"));
  EXPECT_THAT(tex, HasSubstr("fr3\\_w\\_xyz & 0.400 & 0.200 & 0.100 & 0.080 & 0.100 & 0.100 & "
                             "0.050 & 0.020 & 75.00 & 50.00 & 50.00 & 75.00 \\\\"));
  EXPECT_THAT(tex, HasSubstr("s2 & 1.000 & 1.000 & 1.000 & 1.000 & -- & -- & -- & -- & --"));
  EXPECT_THAT(tex, HasSubstr("\\end{table}"));
}

TEST(Table, Csv) {
  const std::string csv = FormatTable(SmallTable(), TableFormat::kCsv);
  EXPECT_EQ(csv,
            "metric,sequence,method,rmse,mean,median,std,f_rmse_percent,f_mean_percent,"
            "f_median_percent,f_std_percent\n"
            "ATE [m],fr3_w_xyz,ORB-SLAM2,0.400000,0.200000,0.100000,0.080000,,,,\n"
            "ATE [m],fr3_w_xyz,Ours,0.100000,0.100000,0.050000,0.020000,75.00,50.00,50.00,75.00\n"
            "ATE [m],s2,ORB-SLAM2,1.000000,1.000000,1.000000,1.000000,,,,\n");
}

TEST(Table, Json) {
  const nlohmann::json j = TableToJson(SmallTable());
  ASSERT_EQ(j.size(), 3u);
  EXPECT_EQ(j[1]["method"], "Ours");
  EXPECT_DOUBLE_EQ(j[1]["improvement_percent"]["rmse"].get<double>(), 75.0);
  EXPECT_TRUE(j[0]["baseline"].get<bool>());
}

TEST(Table, EvaluateRunsFromFiles) {
  TempDir dir;
  const Trajectory gt = testing::MakeCurve(100);
  const auto shifted = [&](double metres) {
    return testing::Transformed(
        gt, geometry::Sim3(Eigen::Quaterniond::Identity(), Eigen::Vector3d(metres, 0, 0), 1.0));
  };
  const std::string gt_path = dir.path() + "/gt.txt";
  WriteTum(gt, gt_path);
  WriteTum(shifted(0.2), dir.path() + "/base.txt");
  WriteTum(shifted(0.05), dir.path() + "/ours.txt");
  EvalRequest settings;
  settings.alignment = "none";
  const std::vector<TableRun> runs = {{"seq", "Ours", gt_path, dir.path() + "/ours.txt", ""},
                                      {"seq", "ORB", gt_path, dir.path() + "/base.txt", ""}};
  const ResultTable table = EvaluateRuns(runs, "ORB", settings);
  ASSERT_EQ(table.methods.size(), 2u);
  EXPECT_EQ(table.methods[0], "ORB");
  EXPECT_NEAR(table.cells[0][0][0]->rmse, 0.2, 1e-12);
  EXPECT_NEAR(Improvement(table.cells[0][0][0]->rmse, table.cells[0][0][1]->rmse), 75.0, 1e-9);
  EXPECT_LT(table.cells[1][0][1]->rmse, 1e-12);  // a constant shift has no drift
  // Without a baseline run for a sequence, the table cannot be made.
  EXPECT_THROW(EvaluateRuns(runs, "Missing", settings), InputError);
  EXPECT_THROW(EvaluateRuns({runs[0], runs[0]}, "", settings), InputError);  // duplicate
}

}  // namespace
}  // namespace moslam::eval
