// Progress of long work (a sequence, a training epoch): periodic lines with count, rate and ETA.
//
// On a terminal the line is redrawn in place as a bar; otherwise (logs, CI) one line is written
// every `interval_s` seconds through spdlog, so a long job never runs silent.
#pragma once

#include <chrono>
#include <cstddef>
#include <string>

namespace moslam {

// "label  120/800 [=====>     ] 15%  12.3 it/s  ETA 55 s" (bar only when `bar` is true).
std::string FormatProgress(const std::string& label, size_t done, size_t total, double elapsed_s,
                           bool bar, const std::string& unit = "it");

class Progress {
 public:
  // total = 0 means unknown: rate is shown, ETA is not.
  Progress(std::string label, size_t total, double interval_s = 2.0, std::string unit = "it");
  ~Progress();
  Progress(const Progress&) = delete;
  Progress& operator=(const Progress&) = delete;

  // Reports `done` items finished; prints when the interval has passed.
  void Update(size_t done);
  // Prints the final line (count, total time, mean rate). Called by the destructor if needed.
  void Finish();

 private:
  using Clock = std::chrono::steady_clock;
  double Elapsed() const;

  std::string label_;
  std::string unit_;
  size_t total_;
  double interval_s_;
  bool terminal_;
  size_t done_ = 0;
  bool finished_ = false;
  Clock::time_point start_;
  Clock::time_point last_print_;
};

}  // namespace moslam
