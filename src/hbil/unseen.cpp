// unseen.cpp: see unseen.h.
#include "hbil/unseen.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>

#include "hbil/spatial_filter.h"

namespace hbil {

namespace {

constexpr int kBands = EscapeProfile::kBands;

// NaN (a camera without a usable focal length) counts as straight down.
int band_of(double sin_elevation) {
  const double u = (sin_elevation + 1.0) * 0.5 * kBands;
  return u >= 0 ? std::min(int(std::min(u, double(kBands))), kBands - 1) : 0;
}

// With carry, how far a surface at the frame's top edge leaves the space above the frame
// open, from the up component of its normal: a wall (up 0) or a ceiling (up < 0) continues
// above the frame and closes it, a floor (up > 0.7) says nothing of what is above it. The
// same, mirrored, for the bottom edge and the space below. A ramp in between; a NaN normal
// counts as a wall.
double facing(double up) {
  const double t = (up - 0.3) / 0.4;
  return t > 0 ? (t < 1 ? t : 1) : 0;
}

}  // namespace

EscapeProfile escape_profile(const ViewGBuffer& v, const Camera& cam, bool carry) {
  struct Sums {
    std::array<double, kBands> all{}, open{};
    // The frame's top and bottom edge rows: all, and open above (top) or below (bottom).
    double top_all = 0, top_open = 0, bottom_all = 0, bottom_open = 0;
  };
  // The edge rows: the top and bottom 1/16 of the frame (at least one sampled row each).
  // In rows, then row sums in order: the same for any thread count.
  // Every step-th pixel of every step-th row, at most about 256 across: a statistic.
  const int step = std::max(1, std::max(v.width, v.height) / 256);
  const int n_rows = v.height > 0 ? (v.height + step - 1) / step : 0;
  const int edge = std::max(step, v.height / 16);
  std::vector<Sums> rows(static_cast<size_t>(n_rows));
  tbb::parallel_for(0, n_rows, [&](int row) {
    Sums& s = rows[size_t(row)];
    const int y = row * step + step / 2 < v.height ? row * step + step / 2 : row * step;
    for (int x = step / 2; x < v.width; x += step) {
      const Vec3d r = cam.unproject(x + 0.5, y + 0.5, 1.0);
      const double len2 = dot(r, r), len = std::sqrt(len2);
      // A pixel's solid angle is its area at z = 1 over |r|^3; up is −y.
      const double w = 1.0 / (len2 * len);
      if (!(w > 0 && w < HUGE_VAL)) continue;
      const int b = band_of(-r.y / len);
      s.all[size_t(b)] += w;
      const size_t i = size_t(y) * v.width + x;
      const bool background = v.is_background(i);
      if (background) s.open[size_t(b)] += w;
      if (!carry) continue;
      if (y < edge) {
        s.top_all += w;
        s.top_open += background ? w : w * facing(-v.normal[i].y);
      }
      if (y >= v.height - edge) {
        s.bottom_all += w;
        s.bottom_open += background ? w : w * facing(v.normal[i].y);
      }
    }
  });
  Sums sum;
  double total = 0;
  for (const Sums& s : rows) {
    for (int b = 0; b < kBands; ++b) {
      sum.all[size_t(b)] += s.all[size_t(b)];
      sum.open[size_t(b)] += s.open[size_t(b)];
      total += s.all[size_t(b)];
    }
    sum.top_all += s.top_all, sum.top_open += s.top_open;
    sum.bottom_all += s.bottom_all, sum.bottom_open += s.bottom_open;
  }
  EscapeProfile p;
  // A band counts as seen with at least 1/1000 of the frame's solid angle (a sliver at the
  // frame's corner says little about its band).
  std::array<bool, kBands> seen{};
  int lo = kBands, hi = -1;
  for (int b = 0; b < kBands; ++b) {
    seen[size_t(b)] = total > 0 && sum.all[size_t(b)] >= 1e-3 * total;
    if (!seen[size_t(b)]) continue;
    p.open[size_t(b)] = float(sum.open[size_t(b)] / sum.all[size_t(b)]);
    lo = std::min(lo, b);
    hi = std::max(hi, b);
  }
  if (hi < 0) {  // nothing seen: every band escapes, or with carry none
    p.open.fill(carry ? 0.f : 1.f);
    return p;
  }
  p.lowest_seen = lo;
  p.highest_seen = hi;
  // With carry, what the frame's top edge says of the elevations above it, and its bottom
  // edge of those below.
  const float above = sum.top_all > 0 ? float(sum.top_open / sum.top_all) : 1.f;
  const float below = sum.bottom_all > 0 ? float(sum.bottom_open / sum.bottom_all) : 1.f;
  for (int b = 0; b < kBands; ++b) {
    if (seen[size_t(b)]) continue;
    // Beyond the frame: open, or with carry as open as the frame's edge on that side. A band
    // inside the frame's range with too little of it takes the nearest seen band below.
    if (b > hi || b < lo) {
      p.open[size_t(b)] = !carry ? 1.f : b > hi ? above : below;
      continue;
    }
    int from = b - 1;
    while (!seen[size_t(from)]) --from;
    p.open[size_t(b)] = p.open[size_t(from)];
  }
  return p;
}

EscapeTable::EscapeTable(const EscapeProfile& profile) {
  // Directions on a grid of equal solid angles: uniform in sin(elevation) (kSub rows per
  // band) and in azimuth. The table's normals have no z, so a direction's cosine with one
  // depends only on the direction's elevation and the cosine of its azimuth.
  constexpr int kSub = 8, kRows = kBands * kSub, kAzimuths = 64;
  constexpr double kPi = 3.14159265358979323846;
  static const std::vector<double> cos_azimuth = [] {
    std::vector<double> c(kAzimuths);
    for (int a = 0; a < kAzimuths; ++a) c[size_t(a)] = std::cos(2 * kPi * (a + 0.5) / kAzimuths);
    return c;
  }();
  for (int k = 0; k < kTable; ++k) {
    const double sn = -1.0 + 2.0 * k / (kTable - 1), cn = std::sqrt(std::max(0.0, 1 - sn * sn));
    double open = 0, all = 0;
    for (int r = 0; r < kRows; ++r) {
      const double s = -1.0 + 2.0 * (r + 0.5) / kRows, ce = std::sqrt(1 - s * s);
      // n·d with n = (cn, −sn, 0), d = (ce cos φ, −s, ce sin φ)
      double row = 0;
      for (const double ca : cos_azimuth) row += std::max(0.0, cn * ce * ca + sn * s);
      all += row;
      open += row * profile.open[size_t(r / kSub)];
    }
    table_[size_t(k)] = all > 0 ? float(open / all) : 0.f;
  }
}

float EscapeTable::at(const Vec3& n) const {
  const float y = -n.y;
  const float s = y > -1.f ? (y < 1.f ? y : 1.f) : -1.f;  // NaN: straight down
  const float u = (s + 1.f) * 0.5f * float(kTable - 1);
  const int k = std::min(int(u), kTable - 2);
  const float a = u - float(k);
  return table_[size_t(k)] * (1.f - a) + table_[size_t(k + 1)] * a;
}

std::vector<Vec3> escape_fill_map(const ViewGBuffer& sv, const std::vector<float>& escape,
                                  const std::vector<float>& reach, const Vec3& fill) {
  std::vector<Vec3> out(sv.pixels());
  tbb::parallel_for(0, sv.height, [&](int y) {
    for (int x = 0; x < sv.width; ++x) {
      const size_t i = size_t(y) * sv.width + x;
      if (sv.is_background(i)) continue;
      const float e = std::clamp(escape[i], 0.f, 1.f), a = reach[i];
      // a <= e: the search leaves no more open than the scene does (or a noisy e says so).
      out[i] = a > e ? fill * (1.f - e / a) : Vec3{};
    }
  });
  return out;
}

std::vector<float> escape_at_view(const ViewGBuffer& v, const ViewGBuffer& sv, int f,
                                  const std::vector<float>& e, float depth_tolerance) {
  const int r = std::max(kEscapeRadius, f / 2);
  std::vector<float> out(sv.pixels());
  tbb::parallel_for(0, sv.height, [&](int j) {
    for (int i = 0; i < sv.width; ++i) {
      const size_t k = size_t(j) * sv.width + i;
      if (sv.is_background(k)) continue;
      const int cx = f * i, cy = f * j;  // the texel's own pixel of v
      auto at = [&](size_t p) { return std::clamp(e[p], 0.f, 1.f); };
      out[k] = surface_mean(v, cx - r, cy - r, cx + r, cy + r, sv.position[k], sv.normal[k],
                            depth_tolerance * sv.position[k].z, at, at(size_t(cy) * v.width + cx));
    }
  });
  return out;
}

std::vector<Vec3> unseen_fill_map(const ViewGBuffer& sv, const EscapeProfile& profile,
                                  const Vec3& fill) {
  const EscapeTable table(profile);
  std::vector<Vec3> out(sv.pixels());
  tbb::parallel_for(0, sv.height, [&](int y) {
    for (int x = 0; x < sv.width; ++x) {
      const size_t i = size_t(y) * sv.width + x;
      if (!sv.is_background(i)) out[i] = fill * (1.f - table.at(sv.normal[i]));
    }
  });
  return out;
}

}  // namespace hbil
