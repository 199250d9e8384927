// error_stats.h: the accuracy measures hbil reports (hbil compare, hbil bench): RMSE, mean
// (signed) error, PSNR with a peak of 1, RMSE relative to the reference's RMS, and the share
// of the reference's energy (sum of values) the test holds, over the pixels a mask keeps.
#pragma once

#include <cmath>
#include <cstddef>
#include <limits>

namespace hbil {

struct ErrorStats {
  double sum = 0, sum_sq = 0;  // of (test − reference)
  double ref_sum = 0, ref_sum_sq = 0, test_sum = 0;
  size_t count = 0;

  void add(double test, double reference) {
    const double e = test - reference;
    sum += e;
    sum_sq += e * e;
    ref_sum += reference;
    ref_sum_sq += reference * reference;
    test_sum += test;
    ++count;
  }
  void add(const ErrorStats& o) {
    sum += o.sum;
    sum_sq += o.sum_sq;
    ref_sum += o.ref_sum;
    ref_sum_sq += o.ref_sum_sq;
    test_sum += o.test_sum;
    count += o.count;
  }
  double mean_error() const { return count ? sum / double(count) : 0.0; }
  double mse() const { return count ? sum_sq / double(count) : 0.0; }
  double rmse() const { return std::sqrt(mse()); }
  // 10 log10(peak² / MSE) with peak 1; +infinity for identical images.
  double psnr() const {
    return mse() > 0 ? -10.0 * std::log10(mse()) : std::numeric_limits<double>::infinity();
  }
  // RMSE / RMS of the reference; NaN for a reference that is zero everywhere.
  double relative_rmse() const {
    return ref_sum_sq > 0 ? std::sqrt(sum_sq / ref_sum_sq)
                          : std::numeric_limits<double>::quiet_NaN();
  }
  // Sum of the test / sum of the reference; NaN when the reference sums to 0.
  double energy_ratio() const {
    return ref_sum != 0 ? test_sum / ref_sum : std::numeric_limits<double>::quiet_NaN();
  }
};

}  // namespace hbil
