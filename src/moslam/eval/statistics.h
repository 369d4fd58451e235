// Summary statistics of per-pose or per-pair errors, defined as numpy computes them, which is what
// TUM's evaluate_ate.py / evaluate_rpe.py and evo print.
#pragma once

#include <cstddef>
#include <vector>

namespace moslam::eval {

struct ErrorStatistics {
  size_t count = 0;
  double rmse = 0;  // sqrt(mean(e^2))
  double mean = 0;
  double median = 0;  // numpy.median: mean of the two middle values for an even count
  double std = 0;     // population standard deviation (numpy.std, ddof = 0)
  double min = 0;
  double max = 0;
};

// Statistics of `values`; all zero (count 0) for an empty list.
ErrorStatistics ComputeStatistics(const std::vector<double>& values);

// numpy.median of `values` (taken by value: it is partially sorted). 0 for an empty list.
double Median(std::vector<double> values);

// Errors with their statistics.
struct ErrorSeries {
  std::vector<double> values;
  ErrorStatistics stats;
};
ErrorSeries MakeSeries(std::vector<double> values);

}  // namespace moslam::eval
