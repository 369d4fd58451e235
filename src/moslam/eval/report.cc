#include "moslam/eval/report.h"

#include <filesystem>

#include <fmt/format.h>

namespace moslam::eval {
namespace {

std::string BaseName(const std::string& path) {
  return std::filesystem::path(path).filename().string();
}

std::string AlignmentDescription(AlignmentMode mode, Convention convention,
                                 const geometry::Sim3& S) {
  switch (mode) {
    case AlignmentMode::kNone:
      return "none";
    case AlignmentMode::kOrigin:
      return "origin (first poses coincide)";
    case AlignmentMode::kSe3:
      return convention == Convention::kTum ? "se3 (Horn)" : "se3 (Umeyama)";
    case AlignmentMode::kSim3:
      return fmt::format("sim3 (Umeyama, scale {:.6f})", S.scale());
  }
  return "?";
}

std::string AssociationDescription(Convention convention, const Trajectory& gt, double max_dt,
                                   double offset) {
  if (!gt.has_timestamps()) return "by index";
  return fmt::format("{} within {} s, offset {} s",
                     convention == Convention::kTum ? "greedy (associate.py)" : "nearest (evo)",
                     max_dt, offset);
}

std::string InputLines(const Trajectory& gt, const Trajectory& est) {
  return fmt::format("  ground truth  {}  ({} poses)\n  estimate      {}  ({} poses)\n", gt.name,
                     gt.size(), est.name, est.size());
}

nlohmann::json InputJson(const Trajectory& t) {
  return {{"path", t.name}, {"poses", t.size()}, {"timestamps", t.has_timestamps()}};
}

nlohmann::json AlignmentJson(AlignmentMode mode, const geometry::Sim3& S) {
  const Eigen::Quaterniond& q = S.rotation();
  const Eigen::Vector3d& t = S.translation();
  return {{"mode", AlignmentModeName(mode)},
          {"rotation_wxyz", {q.w(), q.x(), q.y(), q.z()}},
          {"translation", {t.x(), t.y(), t.z()}},
          {"scale", S.scale()}};
}

std::vector<double> RelativeTimes(const std::vector<double>& times) {
  std::vector<double> out;
  out.reserve(times.size());
  for (const double t : times) out.push_back(t - times.front());
  return out;
}

}  // namespace

std::string FormatStatistics(const ErrorStatistics& stats, const std::string& unit) {
  std::string out = fmt::format("  {:<20} {}\n", "compared_pose_pairs", stats.count);
  const std::pair<const char*, double> rows[] = {{"rmse", stats.rmse},     {"mean", stats.mean},
                                                 {"median", stats.median}, {"std", stats.std},
                                                 {"min", stats.min},       {"max", stats.max}};
  for (const auto& [name, value] : rows) {
    out += fmt::format("  {:<20} {:>12.6f} {}\n", name, value, unit);
  }
  return out;
}

std::string FormatAteReport(const AteResult& result, const Trajectory& gt, const Trajectory& est,
                            bool rotation) {
  const AteOptions& o = result.options;
  std::string out = fmt::format("ATE, convention {}: association {}; alignment {}\n",
                                ConventionName(o.convention),
                                AssociationDescription(o.convention, gt, o.max_dt, o.offset),
                                AlignmentDescription(o.alignment, o.convention, result.alignment));
  out += InputLines(gt, est);
  out += rotation ? "ATE rotation (angle of inv(P_est) Q_gt)\n" : "ATE translation\n";
  out += FormatStatistics(rotation ? result.rotation.stats : result.translation.stats,
                          rotation ? "deg" : "m");
  return out;
}

std::string FormatRpeReport(const RpeResult& result, const Trajectory& gt, const Trajectory& est,
                            bool rotation) {
  const RpeOptions& o = result.options;
  std::string out = fmt::format("RPE, convention {}: delta {} {}{}; association {}; alignment {}\n",
                                ConventionName(o.convention), o.delta, DeltaUnitName(o.delta_unit),
                                o.all_pairs ? ", all pairs" : "",
                                o.convention == Convention::kTum
                                    ? "closest gt stamp within 2x median gt interval"
                                    : AssociationDescription(o.convention, gt, o.max_dt, o.offset),
                                AlignmentDescription(o.alignment, o.convention, result.alignment));
  out += InputLines(gt, est);
  out += rotation ? "RPE rotation\n" : "RPE translation\n";
  out += FormatStatistics(rotation ? result.rotation.stats : result.translation.stats,
                          rotation ? "deg" : "m");
  return out;
}

nlohmann::json StatisticsToJson(const ErrorStatistics& stats) {
  return {{"count", stats.count},   {"rmse", stats.rmse}, {"mean", stats.mean},
          {"median", stats.median}, {"std", stats.std},   {"min", stats.min},
          {"max", stats.max}};
}

namespace {
// The fields ATE and RPE reports share: convention, association, inputs, alignment and the error
// statistics (nlohmann::json keeps keys sorted, so field order is the same either way).
template <typename Result>
nlohmann::json ErrorReportJson(const char* metric, const Result& result, const Trajectory& gt,
                               const Trajectory& est) {
  const auto& o = result.options;
  return {{"metric", metric},
          {"convention", ConventionName(o.convention)},
          {"max_dt", o.max_dt},
          {"offset", o.offset},
          {"ground_truth", InputJson(gt)},
          {"estimate", InputJson(est)},
          {"alignment", AlignmentJson(o.alignment, result.alignment)},
          {"compared_pose_pairs", result.translation.stats.count},
          {"translation_m", StatisticsToJson(result.translation.stats)},
          {"rotation_deg", StatisticsToJson(result.rotation.stats)}};
}
}  // namespace

nlohmann::json AteToJson(const AteResult& result, const Trajectory& gt, const Trajectory& est) {
  return ErrorReportJson("ate", result, gt, est);
}

nlohmann::json RpeToJson(const RpeResult& result, const Trajectory& gt, const Trajectory& est) {
  nlohmann::json json = ErrorReportJson("rpe", result, gt, est);
  json["delta"] = result.options.delta;
  json["delta_unit"] = DeltaUnitName(result.options.delta_unit);
  json["all_pairs"] = result.options.all_pairs;
  return json;
}

TrajectoryPlotData MakeAtePlotData(const AteResult& result, const Trajectory& est, bool rotation) {
  TrajectoryPlotData data;
  const AlignmentMode mode = result.options.alignment;
  data.title = fmt::format("ATE{}: {}",
                           mode == AlignmentMode::kNone   ? ""
                           : mode == AlignmentMode::kSe3  ? ", SE(3)-aligned"
                           : mode == AlignmentMode::kSim3 ? ", Sim(3)-aligned"
                                                          : ", origin-aligned",
                           BaseName(est.name));
  data.times = RelativeTimes(result.poses.times);
  data.reference = result.poses.gt_positions;
  data.estimate = result.poses.est_positions;
  data.errors = rotation ? result.rotation.values : result.translation.values;
  data.error_label = rotation ? "ATE rot. [deg]" : "ATE [m]";
  if (!est.has_timestamps()) data.time_label = "frame";
  return data;
}

TrajectoryPlotData MakeRpePlotData(const RpeResult& result, const Trajectory& est, bool rotation) {
  TrajectoryPlotData data;
  data.title = fmt::format("RPE, delta {} {}: {}", result.options.delta,
                           DeltaUnitName(result.options.delta_unit), BaseName(est.name));
  data.times = RelativeTimes(result.poses.times);
  data.reference = result.poses.gt_positions;
  data.estimate = result.poses.est_positions;
  data.errors = rotation ? result.rotation.values : result.translation.values;
  data.error_label = rotation ? "RPE rot. [deg]" : "RPE trans. [m]";
  if (!est.has_timestamps()) data.time_label = "frame";
  return data;
}

}  // namespace moslam::eval
