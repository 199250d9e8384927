// error_stats.h: the accuracy measures hbil reports (hbil compare): RMSE, mean (signed)
// error and PSNR with a peak of 1, over the pixels a mask keeps.
#pragma once

#include <cmath>
#include <cstddef>
#include <limits>

namespace hbil {

struct ErrorStats {
  double sum = 0, sum_sq = 0;  // of (test − reference)
  size_t count = 0;

  void add(double test, double reference) {
    const double e = test - reference;
    sum += e;
    sum_sq += e * e;
    ++count;
  }
  void add(const ErrorStats& o) {
    sum += o.sum;
    sum_sq += o.sum_sq;
    count += o.count;
  }
  double mean_error() const { return count ? sum / double(count) : 0.0; }
  double mse() const { return count ? sum_sq / double(count) : 0.0; }
  double rmse() const { return std::sqrt(mse()); }
  // 10 log10(peak² / MSE) with peak 1; +infinity for identical images.
  double psnr() const {
    return mse() > 0 ? -10.0 * std::log10(mse()) : std::numeric_limits<double>::infinity();
  }
};

}  // namespace hbil
