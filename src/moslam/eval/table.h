// The paper-style comparison table (as in DS-SLAM / DynaSLAM): per sequence the RMSE, mean,
// median and standard deviation of the ATE and the RPE of a baseline and its variants, and the
// improvement of each variant over the baseline, F = (1 - beta / alpha) * 100 %, alpha being
// the baseline's value and beta the variant's.
//
// Runs are given as `SEQUENCE:METHOD:GT:EST[:GT_TIMES]` (the --run option) or as a CSV manifest
// with the columns sequence,method,gt,est[,gt_times] (an optional header line starting with
// "sequence" and '#' comments are skipped). The baseline is --baseline, or else the method of
// the first run given; every sequence needs a baseline run.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "moslam/eval/evaluate.h"
#include "moslam/eval/statistics.h"

namespace moslam::eval {

struct TableRun {
  std::string sequence;
  std::string method;
  std::string gt_path;
  std::string est_path;
  std::string gt_times;  // optional
};

// "SEQUENCE:METHOD:GT:EST[:GT_TIMES]"; InputError naming the spec when malformed.
TableRun ParseRunSpec(const std::string& spec);
// InputError naming file and line for a malformed row.
std::vector<TableRun> ReadRunManifest(const std::string& path);

enum class TableFormat { kMarkdown, kLatex, kCsv };
// "markdown" (or "md"), "latex", "csv"; InputError otherwise.
TableFormat ParseTableFormat(const std::string& name);

// F = (1 - variant / baseline) * 100; NaN when the baseline is 0.
double Improvement(double baseline, double variant);

struct ResultTable {
  std::vector<std::string> metrics;    // e.g. "ATE [m]"
  std::vector<std::string> sequences;  // in the order first given
  std::vector<std::string> methods;    // the baseline first, then in the order first given
  // cells[metric][sequence][method]; empty when that run was not given.
  std::vector<std::vector<std::vector<std::optional<ErrorStatistics>>>> cells;
};

// Evaluates every run with the settings of `settings` (convention, alignment, delta, ...; its
// inputs are replaced by each run's files) into three metrics: ATE [m], RPE trans. [m] and
// RPE rot. [deg]. An empty `baseline` means the method of the first run.
ResultTable EvaluateRuns(const std::vector<TableRun>& runs, const std::string& baseline,
                         const EvalRequest& settings);

// Markdown and LaTeX print `precision` decimals (improvements: 2); CSV prints one row per
// metric, sequence and method with 6 decimals, improvements empty for the baseline.
std::string FormatTable(const ResultTable& table, TableFormat format, int precision = 4);
nlohmann::json TableToJson(const ResultTable& table);

}  // namespace moslam::eval
