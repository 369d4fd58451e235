// `moslam eval ate|rpe|table`: trajectory evaluation reproducing TUM's and evo's numbers.
// The work is done by moslam::eval (RunEvaluation, EvaluateRuns); this file only maps options.
#include <iostream>
#include <memory>
#include <string>
#include <vector>

#include "commands.h"
#include "moslam/eval/evaluate.h"
#include "moslam/eval/plot.h"
#include "moslam/eval/table.h"
#include "moslam/util/error.h"

namespace moslam::app {
namespace {

using eval::EvalRequest;

// Options of the files and of the association, shared by ate, rpe and table.
struct SharedOptions {
  std::string gt_format = "auto";
  std::string est_format = "auto";
};

void AddFormatOptions(CLI::App* command, SharedOptions* shared, EvalRequest* request) {
  const auto formats = CLI::IsMember({"auto", "tum", "kitti", "euroc"});
  command
      ->add_option("--gt-format", shared->gt_format,
                   "Ground-truth file format: tum, kitti, euroc, or auto (by header/field count)")
      ->check(formats)
      ->capture_default_str();
  command->add_option("--est-format", shared->est_format, "Estimate file format (as --gt-format)")
      ->check(formats)
      ->capture_default_str();
  command
      ->add_option("--gt-times", request->inputs.gt_times,
                   "times.txt giving a KITTI ground truth its timestamps, so that a TUM-format "
                   "estimate is matched by time (default: none)")
      ->check(CLI::ExistingFile);
}

void AddEvaluationOptions(CLI::App* command, EvalRequest* request, bool rpe) {
  command
      ->add_option("--convention", request->convention,
                   "Rules to follow: tum (TUM RGB-D scripts associate.py / evaluate_ate.py / "
                   "evaluate_rpe.py), evo (evo_ape / evo_rpe), or auto (tum when both files have "
                   "timestamps, evo for index-matched files such as KITTI)")
      ->check(CLI::IsMember({"auto", "tum", "evo"}))
      ->capture_default_str();
  command
      ->add_option("--max-dt", request->max_dt,
                   "Largest time difference of associated poses, seconds")
      ->default_str("0.02 for tum (associate.py), 0.01 for evo");
  command
      ->add_option("--offset", request->offset,
                   "Time offset added to the estimate's timestamps, seconds")
      ->capture_default_str();
  command->add_flag("--rotation", request->rotation,
                    "Report the rotation error in degrees instead of the translation error in "
                    "metres (default: off)");
  command->add_flag("--json", request->json,
                    "Print the results as JSON instead of a text table (default: off)");
  if (!rpe) return;
  command
      ->add_option("--delta", request->delta,
                   "Distance between the poses of a pair, in --delta-unit (whole for f)")
      ->capture_default_str();
  command
      ->add_option("--delta-unit", request->delta_unit,
                   "Unit of --delta: f frames, s seconds (tum only), m metres travelled, rad/deg "
                   "rotation")
      ->check(CLI::IsMember({"f", "s", "m", "rad", "deg"}))
      ->default_str("s for tum (evaluate_rpe.py), f for evo");
  command->add_flag("--all-pairs", request->all_pairs,
                    "tum: all pose pairs instead of --delta ones (evaluate_rpe.py without "
                    "--fixed_delta); evo: every pair delta apart, not only consecutive ones "
                    "(evo_rpe --all_pairs) (default: off)");
  command
      ->add_option("--max-pairs", request->max_pairs,
                   "tum: compare at most this many pairs, a seeded random subset beyond "
                   "(evaluate_rpe.py --max_pairs); 0 = all")
      ->capture_default_str();
}

void ApplyFormats(const SharedOptions& shared, EvalRequest* request) {
  request->inputs.gt_format = eval::ParseTrajectoryFormat(shared.gt_format);
  request->inputs.est_format = eval::ParseTrajectoryFormat(shared.est_format);
}

void AddMetricCommand(CLI::App* eval, eval::Metric metric) {
  const bool rpe = metric == eval::Metric::kRpe;
  CLI::App* command = eval->add_subcommand(
      rpe ? "rpe" : "ate",
      rpe ? "Relative pose error (drift) of an estimated trajectory against ground truth"
          : "Absolute trajectory error of an estimated trajectory against ground truth");
  auto request = std::make_shared<EvalRequest>();
  auto shared = std::make_shared<SharedOptions>();
  auto alignment = std::make_shared<std::string>(rpe ? "none" : "se3");
  auto plot_path = std::make_shared<std::string>();
  request->metric = metric;
  command->add_option("GT", request->inputs.gt_path, "Ground-truth trajectory file")->required();
  command->add_option("EST", request->inputs.est_path, "Estimated trajectory file")->required();
  command
      ->add_option("--align", *alignment,
                   rpe ? "Align the estimate first: none, se3, sim3, origin (rigid alignment "
                         "leaves the RPE unchanged; sim3 rescales it)"
                       : "Align the estimate first: none, se3 (evaluate_ate.py; evo -a), sim3 "
                         "(evo -as), origin (evo --align_origin)")
      ->check(CLI::IsMember({"none", "se3", "sim3", "origin"}))
      ->capture_default_str();
  command->add_option("--plot", *plot_path, "Write a plot of the errors to FILE.png or FILE.svg")
      ->default_str("none");
  AddFormatOptions(command, shared.get(), request.get());
  AddEvaluationOptions(command, request.get(), rpe);
  command->callback([request, shared, alignment, plot_path] {
    ApplyFormats(*shared, request.get());
    request->alignment = *alignment;
    request->plot_path = *plot_path;
    const eval::EvalOutput output = eval::RunEvaluation(*request);
    std::cout << output.text << std::flush;
    if (output.plot) eval::WriteTrajectoryPlot(*output.plot, request->plot_path);
  });
}

void AddTableCommand(CLI::App* eval) {
  CLI::App* command = eval->add_subcommand(
      "table",
      "Paper-style table: RMSE, mean, median, SD of ATE and RPE per sequence for a baseline and "
      "its variants, with the improvement F = (1 - variant/baseline) * 100 %");
  auto request = std::make_shared<EvalRequest>();
  auto shared = std::make_shared<SharedOptions>();
  auto runs = std::make_shared<std::vector<std::string>>();
  auto manifest = std::make_shared<std::string>();
  auto baseline = std::make_shared<std::string>();
  auto format = std::make_shared<std::string>("markdown");
  auto precision = std::make_shared<int>(4);
  command->add_option("--run", *runs,
                      "A run as SEQUENCE:METHOD:GT:EST[:GT_TIMES]; repeat for every method and "
                      "sequence (default: none)");
  command
      ->add_option("--manifest", *manifest,
                   "CSV file of runs, columns sequence,method,gt,est[,gt_times] (default: none)")
      ->check(CLI::ExistingFile);
  command->add_option("--baseline", *baseline, "Baseline method")
      ->default_str("the method of the first run");
  command->add_option("--format", *format, "Table format: markdown, latex, csv")
      ->check(CLI::IsMember({"markdown", "md", "latex", "csv"}))
      ->capture_default_str();
  command->add_option("--precision", *precision, "Decimals of the values (markdown, latex)")
      ->check(CLI::Range(0, 12))
      ->capture_default_str();
  command
      ->add_option("--align", request->alignment,
                   "Align each estimate first: none, se3, sim3, origin")
      ->check(CLI::IsMember({"none", "se3", "sim3", "origin"}))
      ->default_str("se3 for the ATE, none for the RPE");
  AddFormatOptions(command, shared.get(), request.get());
  AddEvaluationOptions(command, request.get(), /*rpe=*/true);
  command->callback([=] {
    ApplyFormats(*shared, request.get());
    std::vector<eval::TableRun> all;
    if (!manifest->empty()) all = eval::ReadRunManifest(*manifest);
    for (const std::string& spec : *runs) all.push_back(eval::ParseRunSpec(spec));
    if (all.empty()) ThrowInput("give the runs with --run or --manifest");
    const eval::ResultTable table = eval::EvaluateRuns(all, *baseline, *request);
    if (request->json) {
      std::cout << eval::TableToJson(table).dump(2) << "\n";
    } else {
      std::cout << eval::FormatTable(table, eval::ParseTableFormat(*format), *precision);
    }
    std::cout << std::flush;
  });
}

}  // namespace

void AddEvalCommand(CLI::App& app) {
  CLI::App* eval = app.add_subcommand(
      "eval", "Evaluate trajectories: ATE, RPE (TUM RGB-D or evo conventions), result tables");
  eval->require_subcommand(1);
  AddMetricCommand(eval, eval::Metric::kAte);
  AddMetricCommand(eval, eval::Metric::kRpe);
  AddTableCommand(eval);
}

}  // namespace moslam::app
