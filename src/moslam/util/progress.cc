#include "moslam/util/progress.h"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include <fmt/format.h>
#include <spdlog/spdlog.h>

namespace moslam {

namespace {

std::string FormatDuration(double seconds) {
  if (!std::isfinite(seconds) || seconds < 0) return "?";
  const long s = std::lround(seconds);
  if (s < 60) return fmt::format("{} s", s);
  if (s < 3600) return fmt::format("{}:{:02d} min", s / 60, s % 60);
  return fmt::format("{}:{:02d} h", s / 3600, (s % 3600) / 60);
}

}  // namespace

std::string FormatProgress(const std::string& label, size_t done, size_t total, double elapsed_s,
                           bool bar, const std::string& unit) {
  const double rate = elapsed_s > 0 ? static_cast<double>(done) / elapsed_s : 0.0;
  std::string line = fmt::format("{}  {}", label, done);
  if (total > 0) {
    const double fraction = std::min(1.0, static_cast<double>(done) / static_cast<double>(total));
    line += fmt::format("/{}", total);
    if (bar) {
      constexpr int kWidth = 24;
      const int filled = static_cast<int>(fraction * kWidth);
      line += " [" + std::string(filled, '=') + (filled < kWidth ? ">" : "") +
              std::string(std::max(0, kWidth - filled - 1), ' ') + "]";
    }
    line += fmt::format(" {:3.0f}%", 100.0 * fraction);
  }
  line += fmt::format("  {:.1f} {}/s", rate, unit);
  if (total > 0 && done < total && rate > 0) {
    line += "  ETA " + FormatDuration(static_cast<double>(total - done) / rate);
  } else if (total > 0 && done >= total) {
    line += "  in " + FormatDuration(elapsed_s);
  }
  return line;
}

Progress::Progress(std::string label, size_t total, double interval_s, std::string unit)
    : label_(std::move(label)),
      unit_(std::move(unit)),
      total_(total),
      interval_s_(interval_s),
      terminal_(isatty(fileno(stderr)) != 0),
      start_(Clock::now()),
      last_print_(start_) {}

Progress::~Progress() { Finish(); }

double Progress::Elapsed() const {
  return std::chrono::duration<double>(Clock::now() - start_).count();
}

void Progress::Update(size_t done) {
  done_ = done;
  const auto now = Clock::now();
  const double since = std::chrono::duration<double>(now - last_print_).count();
  // On a terminal, redraw often; in logs, only every interval.
  if (since < (terminal_ ? 0.1 : interval_s_)) return;
  last_print_ = now;
  const std::string line = FormatProgress(label_, done_, total_, Elapsed(), terminal_, unit_);
  if (terminal_) {
    std::fprintf(stderr, "\r%s\033[K", line.c_str());
    std::fflush(stderr);
  } else {
    spdlog::info("{}", line);
  }
}

void Progress::Finish() {
  if (finished_) return;
  finished_ = true;
  const std::string line = FormatProgress(label_, done_, total_, Elapsed(), false, unit_);
  if (terminal_) std::fprintf(stderr, "\r\033[K");
  spdlog::info("{}", line);
}

}  // namespace moslam
