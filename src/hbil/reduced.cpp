// reduced.cpp: see reduced.h.
#include "hbil/reduced.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

#include "hbil/spatial_filter.h"

namespace hbil {

int effective_search_scale(const Params& p, int width, int height) {
  if (p.search_scale >= 1) return p.search_scale;
  return std::max(1, std::min(width, height) / kAutoSearchSide);
}

std::string describe_search(const Params& p, int width, int height) {
  const int n = effective_search_scale(p, width, height);
  const std::string side = std::to_string(n);
  std::string s =
      n == 1 ? "every pixel" : "one pixel of every " + side + "x" + side + " block, upsampled";
  if (p.search_scale == 0)
    s += " (search_scale auto for " + std::to_string(width) + "x" + std::to_string(height) + ")";
  return s;
}

namespace {

// fn(k, own, i, j) for each texel (i, j) of lo = reduce_view(v, f), rows in parallel: k is its
// index in lo, own the index in v of its own pixel (f i, f j).
template <class Fn>
void for_each_texel(const ViewGBuffer& v, const ViewGBuffer& lo, int f, Fn fn) {
  tbb::parallel_for(0, lo.height, [&](int j) {
    for (int i = 0; i < lo.width; ++i)
      fn(size_t(j) * lo.width + i, size_t(f * j) * v.width + f * i, i, j);
  });
}

}  // namespace

ViewGBuffer reduce_view(const ViewGBuffer& v, int f) {
  ViewGBuffer lo;
  lo.width = reduced_extent(v.width, f);
  lo.height = reduced_extent(v.height, f);
  lo.scale = v.scale * f;
  lo.position.resize(lo.pixels());
  lo.normal.resize(lo.pixels());
  if (!v.thickness.empty()) lo.thickness.resize(lo.pixels());
  for_each_texel(v, lo, f, [&](size_t k, size_t src, int, int) {
    lo.position[k] = v.position[src];
    lo.normal[k] = v.normal[src];
    if (!lo.thickness.empty()) lo.thickness[k] = v.thickness[src];
  });
  return lo;
}

std::vector<float> reduce_motion(const ViewGBuffer& v, const ViewGBuffer& lo, int f,
                                 const std::vector<float>& motion) {
  std::vector<float> out(2 * lo.pixels());
  const float inv_f = 1.f / float(f);
  for_each_texel(v, lo, f, [&](size_t k, size_t src, int, int) {
    out[2 * k] = motion[2 * src] * inv_f;
    out[2 * k + 1] = motion[2 * src + 1] * inv_f;
  });
  return out;
}

std::vector<Vec3> reduce_radiance(const ViewGBuffer& v, const ViewGBuffer& lo, int f,
                                  const std::vector<Vec3>& L, float depth_tolerance) {
  std::vector<Vec3> out(lo.pixels());
  for_each_texel(v, lo, f, [&](size_t k, size_t own, int i, int j) {
    if (lo.is_background(k)) return;
    // The texel's f x f block; its own pixel (the block's first) where nothing passes.
    out[k] = surface_mean(
        v, f * i, f * j, f * i + f - 1, f * j + f - 1, lo.position[k], lo.normal[k],
        depth_tolerance * lo.position[k].z, [&](size_t p) { return L[p]; }, L[own]);
  });
  return out;
}

namespace {

// Pixel (x, y) of a frame whose texels lie every f pixels: the texels (i0, j0) to
// (i0 + 1, j0 + 1) around it and its bilinear weight on each.
struct TexelCell {
  int i0, j0;
  float tx, ty;
  TexelCell(int x, int y, int f) : i0(x / f), j0(y / f) {
    const float inv_f = 1.f / float(f);
    tx = float(x - f * i0) * inv_f;
    ty = float(y - f * j0) * inv_f;
  }
  float weight(int di, int dj) const { return (di ? tx : 1.f - tx) * (dj ? ty : 1.f - ty); }
};

// What pixel (x, y) of v takes from lo (UpsamplePlan's encoding).
std::uint32_t upsample_choice(const ViewGBuffer& v, const ViewGBuffer& lo, int f, int x, int y,
                              float depth_tolerance) {
  const size_t p = size_t(y) * v.width + x;
  if (v.is_background(p)) return UpsamplePlan::kNone;
  const Vec3 &P = v.position[p], &n = v.normal[p];
  const float tol = depth_tolerance * P.z;
  const TexelCell cell(x, y, f);
  const int i0 = cell.i0, j0 = cell.j0;
  std::uint32_t mask = 0;
  for (int dj = 0; dj < 2; ++dj)
    for (int di = 0; di < 2; ++di) {
      const int i = i0 + di, j = j0 + dj;
      const float wk = cell.weight(di, dj);
      if (!(wk > 0.f) || i >= lo.width || j >= lo.height) continue;
      const size_t k = size_t(j) * lo.width + i;
      if (lo.is_background(k) || !same_surface(P, n, lo.position[k], lo.normal[k], tol)) continue;
      mask |= 1u << (2 * dj + di);
    }
  if (mask) return UpsamplePlan::kBilinear | mask;
  // No texel on this pixel's surface: the nearest to its tangent plane that faces its way,
  // among the 4x4 texels around it.
  float best = std::numeric_limits<float>::infinity();
  size_t at = 0;
  for (int j = std::max(j0 - 1, 0); j <= std::min(j0 + 2, lo.height - 1); ++j)
    for (int i = std::max(i0 - 1, 0); i <= std::min(i0 + 2, lo.width - 1); ++i) {
      const size_t k = size_t(j) * lo.width + i;
      if (lo.is_background(k) || dot(lo.normal[k], n) <= 0.f) continue;
      const float dist = std::fabs(dot(lo.position[k] - P, n));
      if (dist < best) best = dist, at = k;
    }
  return best == std::numeric_limits<float>::infinity() ? UpsamplePlan::kNone : std::uint32_t(at);
}

// Pixel (x, y) of `out` from h by its choice (upsample_choice).
void upsample_apply(std::uint32_t choice, const ViewGBuffer& v, const ViewGBuffer& lo, int f, int x,
                    int y, const HorizonImage& h, HorizonImage& out) {
  if (choice == UpsamplePlan::kNone) return;
  HorizonMean mean;
  if (choice & UpsamplePlan::kBilinear) {
    const TexelCell cell(x, y, f);
    for (int dj = 0; dj < 2; ++dj)
      for (int di = 0; di < 2; ++di) {
        if (!(choice & (1u << (2 * dj + di)))) continue;
        mean.add(h, size_t(cell.j0 + dj) * lo.width + (cell.i0 + di), cell.weight(di, dj));
      }
  } else {
    mean.add(h, choice, 1.f);
  }
  mean.store(out, size_t(y) * v.width + x);
}

// An image of v's size to upsample h into: background pixels keep the unoccluded default.
HorizonImage upsample_target(const ViewGBuffer& v, const HorizonImage& h) {
  if (!h.irradiance_only()) return unoccluded_image(v, !h.irradiance.empty());
  HorizonImage out;
  out.width = v.width;
  out.height = v.height;
  out.irradiance.assign(v.pixels(), Vec3{});
  return out;
}

}  // namespace

HorizonImage upsample_horizon(const ViewGBuffer& v, const ViewGBuffer& lo, int f,
                              const HorizonImage& h, float depth_tolerance) {
  HorizonImage out = upsample_target(v, h);
  tbb::parallel_for(0, v.height, [&](int y) {
    for (int x = 0; x < v.width; ++x)
      upsample_apply(upsample_choice(v, lo, f, x, y, depth_tolerance), v, lo, f, x, y, h, out);
  });
  return out;
}

UpsamplePlan plan_upsample(const ViewGBuffer& v, const ViewGBuffer& lo, int f,
                           float depth_tolerance) {
  UpsamplePlan plan;
  plan.f = f;
  plan.choice.resize(v.pixels());
  tbb::parallel_for(0, v.height, [&](int y) {
    for (int x = 0; x < v.width; ++x)
      plan.choice[size_t(y) * v.width + x] = upsample_choice(v, lo, f, x, y, depth_tolerance);
  });
  return plan;
}

HorizonImage upsample_horizon(const ViewGBuffer& v, const ViewGBuffer& lo, const UpsamplePlan& plan,
                              const HorizonImage& h) {
  HorizonImage out = upsample_target(v, h);
  tbb::parallel_for(0, v.height, [&](int y) {
    for (int x = 0; x < v.width; ++x)
      upsample_apply(plan.choice[size_t(y) * v.width + x], v, lo, plan.f, x, y, h, out);
  });
  return out;
}

std::vector<float> upsample_count(const ViewGBuffer& v, const ViewGBuffer& lo,
                                  const UpsamplePlan& plan, const std::vector<float>& x) {
  std::vector<float> out(v.pixels(), 0.f);
  const int f = plan.f;
  tbb::parallel_for(0, v.height, [&](int y) {
    for (int px = 0; px < v.width; ++px) {
      const size_t p = size_t(y) * v.width + px;
      const std::uint32_t choice = plan.choice[p];
      if (choice == UpsamplePlan::kNone) {
        if (!v.is_background(p)) out[p] = 1.f;
        continue;
      }
      if (!(choice & UpsamplePlan::kBilinear)) {
        out[p] = x[choice];
        continue;
      }
      // The texel of the largest bilinear weight among those on the pixel's surface (the
      // first in the mask's order on a tie).
      const TexelCell cell(px, y, f);
      float best = -1.f;
      for (int dj = 0; dj < 2; ++dj)
        for (int di = 0; di < 2; ++di) {
          if (!(choice & (1u << (2 * dj + di)))) continue;
          const float wk = cell.weight(di, dj);
          if (wk > best) best = wk, out[p] = x[size_t(cell.j0 + dj) * lo.width + (cell.i0 + di)];
        }
    }
  });
  return out;
}

}  // namespace hbil
