#include "moslam/eval/statistics.h"

#include <algorithm>
#include <cmath>

namespace moslam::eval {

double Median(std::vector<double> values) {
  if (values.empty()) return 0;
  const size_t n = values.size();
  const auto middle = values.begin() + static_cast<std::ptrdiff_t>(n / 2);
  std::nth_element(values.begin(), middle, values.end());
  const double upper = *middle;
  if (n % 2 == 1) return upper;
  const double lower = *std::max_element(values.begin(), middle);
  // numpy.median takes np.mean of the two middle values: (lower + upper) / 2.
  return (lower + upper) / 2;
}

ErrorStatistics ComputeStatistics(const std::vector<double>& values) {
  ErrorStatistics s;
  s.count = values.size();
  if (values.empty()) return s;
  const double n = static_cast<double>(values.size());
  double sum = 0;
  double sum_squares = 0;
  s.min = values.front();
  s.max = values.front();
  for (const double v : values) {
    sum += v;
    sum_squares += v * v;
    s.min = std::min(s.min, v);
    s.max = std::max(s.max, v);
  }
  s.mean = sum / n;
  s.rmse = std::sqrt(sum_squares / n);
  // Two passes, as numpy.std: the one-pass formula loses digits when std << mean.
  double sum_deviations = 0;
  for (const double v : values) sum_deviations += (v - s.mean) * (v - s.mean);
  s.std = std::sqrt(sum_deviations / n);
  s.median = Median(values);
  return s;
}

ErrorSeries MakeSeries(std::vector<double> values) {
  ErrorSeries series;
  series.stats = ComputeStatistics(values);
  series.values = std::move(values);
  return series;
}

}  // namespace moslam::eval
