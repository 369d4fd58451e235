#include "moslam/eval/table.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <limits>
#include <map>

#include <fmt/format.h>

#include "moslam/eval/report.h"
#include "moslam/util/error.h"
#include "moslam/util/strings.h"
#include "moslam/util/text_file.h"

namespace moslam::eval {
namespace {

// The four statistics of the table, in column order.
constexpr const char* kStatNames[] = {"RMSE", "Mean", "Median", "SD"};
std::array<double, 4> TableStats(const ErrorStatistics& s) {
  return {s.rmse, s.mean, s.median, s.std};
}

std::vector<std::string> SplitOn(const std::string& text, char separator) {
  std::vector<std::string> parts;
  size_t begin = 0;
  while (true) {
    const size_t end = text.find(separator, begin);
    parts.emplace_back(Trim(text.substr(begin, end - begin)));
    if (end == std::string::npos) break;
    begin = end + 1;
  }
  return parts;
}

std::optional<TableRun> RunFromFields(const std::vector<std::string>& f) {
  if (f.size() < 4 || f.size() > 5) return std::nullopt;
  for (const std::string& field : f) {
    if (field.empty()) return std::nullopt;
  }
  return TableRun{f[0], f[1], f[2], f[3], f.size() == 5 ? f[4] : ""};
}

size_t IndexOf(std::vector<std::string>* names, const std::string& name) {
  const auto it = std::find(names->begin(), names->end(), name);
  if (it != names->end()) return static_cast<size_t>(it - names->begin());
  names->push_back(name);
  return names->size() - 1;
}

std::string FormatNumber(double value, int precision) {
  return fmt::format("{:.{}f}", value, precision);
}

std::string FormatImprovement(double f, const char* missing) {
  return std::isnan(f) ? std::string(missing) : fmt::format("{:.2f}", f);
}

std::string EscapeLatex(const std::string& text) {
  std::string out;
  for (const char c : text) {
    if (c == '_' || c == '%' || c == '&' || c == '#' || c == '$' || c == '{' || c == '}') {
      out += '\\';
      out += c;
    } else if (c == '\\') {
      out += "\\textbackslash{}";
    } else if (c == '~' || c == '^') {
      out += fmt::format("\\{}{{}}", c);
    } else {
      out += c;
    }
  }
  return out;
}

std::string EscapeMarkdown(const std::string& text) {
  std::string out;
  for (const char c : text) {
    if (c == '|') out += '\\';
    out += c;
  }
  return out;
}

std::string CsvField(const std::string& text) {
  if (text.find_first_of(",\"\n") == std::string::npos) return text;
  std::string out = "\"";
  for (const char c : text) out += c == '"' ? std::string("\"\"") : std::string(1, c);
  return out + "\"";
}

// The cells of one table row (one metric and sequence): per method its four statistics, then
// per variant its four improvements; `missing` where a run is absent.
struct RowText {
  std::vector<std::string> values;
  std::vector<std::string> improvements;
};
RowText MakeRow(const std::vector<std::optional<ErrorStatistics>>& cells, int precision,
                const char* missing) {
  RowText row;
  for (const auto& cell : cells) {
    for (size_t k = 0; k < 4; ++k) {
      row.values.push_back(cell ? FormatNumber(TableStats(*cell)[k], precision) : missing);
    }
  }
  const std::optional<ErrorStatistics>& base = cells.front();
  for (size_t m = 1; m < cells.size(); ++m) {
    for (size_t k = 0; k < 4; ++k) {
      row.improvements.push_back(
          base && cells[m]
              ? FormatImprovement(Improvement(TableStats(*base)[k], TableStats(*cells[m])[k]),
                                  missing)
              : missing);
    }
  }
  return row;
}

std::string FormatMarkdown(const ResultTable& t, int precision) {
  std::string out;
  for (size_t a = 0; a < t.metrics.size(); ++a) {
    if (a > 0) out += "\n";
    out += fmt::format("**{}**\n\n| Sequence |", EscapeMarkdown(t.metrics[a]));
    size_t columns = 1;
    for (const std::string& method : t.methods) {
      for (const char* stat : kStatNames) {
        out += fmt::format(" {} {} |", EscapeMarkdown(method), stat);
        ++columns;
      }
    }
    for (size_t m = 1; m < t.methods.size(); ++m) {
      for (const char* stat : kStatNames) {
        out += fmt::format(" F {} {} (%) |", EscapeMarkdown(t.methods[m]), stat);
        ++columns;
      }
    }
    out += "\n|---|";
    for (size_t c = 1; c < columns; ++c) out += "---:|";
    out += "\n";
    for (size_t s = 0; s < t.sequences.size(); ++s) {
      const RowText row = MakeRow(t.cells[a][s], precision, "–");
      out += fmt::format("| {} |", EscapeMarkdown(t.sequences[s]));
      for (const std::string& v : row.values) out += " " + v + " |";
      for (const std::string& v : row.improvements) out += " " + v + " |";
      out += "\n";
    }
  }
  return out;
}

std::string FormatLatex(const ResultTable& t, int precision) {
  std::string out;
  const size_t groups = 2 * t.methods.size() - 1;
  for (size_t a = 0; a < t.metrics.size(); ++a) {
    if (a > 0) out += "\n";
    out += "\\begin{table}[t]\n\\centering\n";
    out += fmt::format("\\caption{{{}}}\n\\begin{{tabular}}{{l", EscapeLatex(t.metrics[a]));
    for (size_t g = 0; g < groups; ++g) out += "|cccc";
    out += "}\n\\hline\n";
    for (size_t g = 0; g < groups; ++g) {
      const bool variant_f = g >= t.methods.size();
      const std::string name =
          variant_f ? "Improvement " + t.methods[g - t.methods.size() + 1] + " (%)" : t.methods[g];
      out += fmt::format(" & \\multicolumn{{4}}{{c{}}}{{{}}}", g + 1 < groups ? "|" : "",
                         EscapeLatex(name));
    }
    out += " \\\\\nSequence";
    for (size_t g = 0; g < groups; ++g) out += " & RMSE & Mean & Median & S.D.";
    out += " \\\\\n\\hline\n";
    for (size_t s = 0; s < t.sequences.size(); ++s) {
      const RowText row = MakeRow(t.cells[a][s], precision, "--");
      out += EscapeLatex(t.sequences[s]);
      for (const std::string& v : row.values) out += " & " + v;
      for (const std::string& v : row.improvements) out += " & " + v;
      out += " \\\\\n";
    }
    out += "\\hline\n\\end{tabular}\n\\end{table}\n";
  }
  return out;
}

std::string FormatCsv(const ResultTable& t) {
  std::string out =
      "metric,sequence,method,rmse,mean,median,std,f_rmse_percent,f_mean_percent,"
      "f_median_percent,f_std_percent\n";
  for (size_t a = 0; a < t.metrics.size(); ++a) {
    for (size_t s = 0; s < t.sequences.size(); ++s) {
      const auto& base = t.cells[a][s].front();
      for (size_t m = 0; m < t.methods.size(); ++m) {
        const auto& cell = t.cells[a][s][m];
        if (!cell) continue;
        out += fmt::format("{},{},{}", CsvField(t.metrics[a]), CsvField(t.sequences[s]),
                           CsvField(t.methods[m]));
        for (const double v : TableStats(*cell)) out += "," + FormatNumber(v, 6);
        for (size_t k = 0; k < 4; ++k) {
          out += ",";
          if (m > 0 && base) {
            out += FormatImprovement(Improvement(TableStats(*base)[k], TableStats(*cell)[k]), "");
          }
        }
        out += "\n";
      }
    }
  }
  return out;
}

}  // namespace

TableRun ParseRunSpec(const std::string& spec) {
  const std::optional<TableRun> run = RunFromFields(SplitOn(spec, ':'));
  if (!run) {
    ThrowInput(
        "run '{}' is not SEQUENCE:METHOD:GT:EST[:GT_TIMES] (use a manifest for paths "
        "with ':')",
        spec);
  }
  return *run;
}

std::vector<TableRun> ReadRunManifest(const std::string& path) {
  std::vector<TableRun> runs;
  std::map<std::pair<std::string, std::string>, int> line_of;  // (sequence, method) -> line
  for (const TextLine& line : ReadDataLines(path)) {
    if (runs.empty() && StartsWith(ToLower(line.text), "sequence")) continue;  // header
    const std::optional<TableRun> run = RunFromFields(SplitOn(line.text, ','));
    if (!run) {
      ThrowAtLine(path, line.number, "expected sequence,method,gt,est[,gt_times]");
    }
    // Checked here so that a path the row gets wrong (a quoted field with a comma splits the row
    // elsewhere) is reported at its line, not as a lone file name later.
    for (const auto& [what, file] :
         {std::pair{"gt", run->gt_path}, {"est", run->est_path}, {"gt_times", run->gt_times}}) {
      std::error_code ec;
      if (!file.empty() && !std::filesystem::is_regular_file(file, ec)) {
        ThrowAtLine(path, line.number,
                    fmt::format("{} '{}' is not an existing file", what, Excerpt(file, 200)));
      }
    }
    const auto [it, added] = line_of.emplace(std::pair{run->sequence, run->method}, line.number);
    if (!added) {
      ThrowAtLine(path, line.number,
                  fmt::format("a second run of method '{}' on sequence '{}' (the first: line {})",
                              Excerpt(run->method), Excerpt(run->sequence), it->second));
    }
    runs.push_back(*run);
  }
  if (runs.empty()) ThrowInFile(path, "lists no runs");
  return runs;
}

TableFormat ParseTableFormat(const std::string& name) {
  const std::string lower = ToLower(name);
  if (lower == "markdown" || lower == "md") return TableFormat::kMarkdown;
  if (lower == "latex") return TableFormat::kLatex;
  if (lower == "csv") return TableFormat::kCsv;
  ThrowInput("unknown table format '{}' (markdown, latex, csv)", name);
}

double Improvement(double baseline, double variant) {
  if (baseline == 0) return std::numeric_limits<double>::quiet_NaN();
  return (1.0 - variant / baseline) * 100.0;
}

ResultTable EvaluateRuns(const std::vector<TableRun>& runs, const std::string& baseline,
                         const EvalRequest& settings) {
  if (runs.empty()) ThrowInput("the table needs at least one run");
  ResultTable table;
  table.metrics = {"ATE [m]", "RPE trans. [m]", "RPE rot. [deg]"};
  table.methods.push_back(baseline.empty() ? runs.front().method : baseline);
  for (const TableRun& run : runs) {
    IndexOf(&table.sequences, run.sequence);
    IndexOf(&table.methods, run.method);
  }
  table.cells.assign(table.metrics.size(),
                     std::vector<std::vector<std::optional<ErrorStatistics>>>(
                         table.sequences.size(),
                         std::vector<std::optional<ErrorStatistics>>(table.methods.size())));
  for (const TableRun& run : runs) {
    const size_t s = IndexOf(&table.sequences, run.sequence);
    const size_t m = IndexOf(&table.methods, run.method);
    if (table.cells[0][s][m]) {
      ThrowInput("two runs of method '{}' on sequence '{}'", Excerpt(run.method),
                 Excerpt(run.sequence));
    }
    EvalRequest request = settings;
    request.inputs.gt_path = run.gt_path;
    request.inputs.est_path = run.est_path;
    request.inputs.gt_times = run.gt_times;
    const TrajectoryPair trajectories = LoadTrajectories(request.inputs);
    const AteResult ate =
        ComputeAte(trajectories.gt, trajectories.est, MakeAteOptions(request, trajectories));
    const RpeResult rpe =
        ComputeRpe(trajectories.gt, trajectories.est, MakeRpeOptions(request, trajectories));
    table.cells[0][s][m] = ate.translation.stats;
    table.cells[1][s][m] = rpe.translation.stats;
    table.cells[2][s][m] = rpe.rotation.stats;
  }
  for (size_t s = 0; s < table.sequences.size(); ++s) {
    if (!table.cells[0][s][0]) {
      ThrowInput("sequence '{}' has no run of the baseline '{}'", Excerpt(table.sequences[s]),
                 Excerpt(table.methods[0]));
    }
  }
  return table;
}

std::string FormatTable(const ResultTable& table, TableFormat format, int precision) {
  switch (format) {
    case TableFormat::kMarkdown:
      return FormatMarkdown(table, precision);
    case TableFormat::kLatex:
      return FormatLatex(table, precision);
    case TableFormat::kCsv:
      return FormatCsv(table);
  }
  return {};
}

nlohmann::json TableToJson(const ResultTable& table) {
  nlohmann::json rows = nlohmann::json::array();
  for (size_t a = 0; a < table.metrics.size(); ++a) {
    for (size_t s = 0; s < table.sequences.size(); ++s) {
      const auto& base = table.cells[a][s].front();
      for (size_t m = 0; m < table.methods.size(); ++m) {
        const auto& cell = table.cells[a][s][m];
        if (!cell) continue;
        nlohmann::json row = {{"metric", table.metrics[a]},
                              {"sequence", table.sequences[s]},
                              {"method", table.methods[m]},
                              {"baseline", m == 0},
                              {"statistics", StatisticsToJson(*cell)}};
        if (m > 0 && base) {
          nlohmann::json f;
          const auto b = TableStats(*base);
          const auto v = TableStats(*cell);
          const char* keys[] = {"rmse", "mean", "median", "std"};
          for (size_t k = 0; k < 4; ++k) {
            const double value = Improvement(b[k], v[k]);
            f[keys[k]] = std::isnan(value) ? nlohmann::json(nullptr) : nlohmann::json(value);
          }
          row["improvement_percent"] = f;
        }
        rows.push_back(row);
      }
    }
  }
  return rows;
}

}  // namespace moslam::eval
