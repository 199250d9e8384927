// pushpull.cpp: see pushpull.h.
#include "hbil/pushpull.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <string>

#include "hbil/error.h"

namespace hbil {

namespace {

constexpr int kMaxClusters = 4;
constexpr float kBackgroundDepth = 1e30f;

bool is_background_depth(float z) {
  return !(z > 0.f && z < kBackgroundDepth);
}

// One pyramid level above the pixels: cell c owns clusters [begin[c], begin[c + 1]).
struct Level {
  int w = 0, h = 0;
  std::vector<uint32_t> begin;
  std::vector<float> lo, hi;      // depth interval
  std::vector<uint32_t> n, nv;    // pixels covered, valid pixels among them
  std::vector<float> mean;        // clusters * channels: mean of the valid pixels
  std::vector<float> fill;        // clusters * channels: pushed value
  std::vector<uint8_t> has_fill;  // per cluster
  size_t clusters() const { return lo.size(); }
};

// A child's cluster as seen by the pull.
struct Candidate {
  float lo, hi;
  uint32_t n, nv;
  const float* mean;  // channels floats, or null when nv == 0
  int order;          // position among the cell's candidates (tie break)
};

// The clusters one row of parent cells produces, concatenated afterwards in row order.
struct RowClusters {
  std::vector<uint32_t> count;  // per cell
  std::vector<float> lo, hi, mean;
  std::vector<uint32_t> n, nv;
};

// Merges the candidates of one cell and appends the resulting clusters to `out`.
void merge_cell(std::vector<Candidate>& cand, int channels, float tol, RowClusters& out,
                std::vector<double>& sums) {
  std::sort(cand.begin(), cand.end(), [](const Candidate& a, const Candidate& b) {
    return a.lo < b.lo || (a.lo == b.lo && a.order < b.order);
  });
  struct Group {
    float lo, hi;
    uint64_t n, nv;
    size_t sum;  // offset into sums
  };
  Group groups[16 * kMaxClusters];
  int ng = 0;
  sums.clear();
  for (const Candidate& c : cand) {
    if (ng == 0 || c.lo > groups[ng - 1].hi * (1.f + tol)) {
      groups[ng++] = {c.lo, c.hi, 0, 0, sums.size()};
      sums.resize(sums.size() + size_t(channels), 0.0);
    }
    Group& g = groups[ng - 1];
    g.hi = std::max(g.hi, c.hi);
    g.n += c.n;
    g.nv += c.nv;
    if (c.nv > 0)
      for (int k = 0; k < channels; ++k) sums[g.sum + k] += double(c.nv) * double(c.mean[k]);
  }
  // Too many layers: merge the neighbouring pair with the smallest relative gap.
  while (ng > kMaxClusters) {
    int best = 0;
    double best_gap = 0;
    for (int k = 0; k + 1 < ng; ++k) {
      const double gap = (double(groups[k + 1].lo) - groups[k].hi) / groups[k].hi;
      if (k == 0 || gap < best_gap) best = k, best_gap = gap;
    }
    Group& a = groups[best];
    const Group& b = groups[best + 1];
    a.hi = std::max(a.hi, b.hi);
    a.n += b.n;
    a.nv += b.nv;
    for (int k = 0; k < channels; ++k) sums[a.sum + k] += sums[b.sum + k];
    std::copy(groups + best + 2, groups + ng, groups + best + 1);
    --ng;
  }
  out.count.push_back(uint32_t(ng));
  for (int k = 0; k < ng; ++k) {
    const Group& g = groups[k];
    out.lo.push_back(g.lo);
    out.hi.push_back(g.hi);
    out.n.push_back(uint32_t(g.n));
    out.nv.push_back(uint32_t(g.nv));
    for (int c = 0; c < channels; ++c)
      out.mean.push_back(g.nv > 0 ? float(sums[g.sum + c] / double(g.nv)) : 0.f);
  }
}

// Builds the level above: `child_candidates(cx, cy, vec)` appends the candidates of child
// cell (cx, cy), which lies inside the child level.
template <typename ChildFn>
Level pull(int child_w, int child_h, int channels, float tol, ChildFn child_candidates) {
  Level L;
  L.w = (child_w + 1) / 2;
  L.h = (child_h + 1) / 2;
  std::vector<RowClusters> rows(size_t(L.h));
  tbb::parallel_for(0, L.h, [&](int y) {
    RowClusters& out = rows[size_t(y)];
    std::vector<Candidate> cand;
    std::vector<double> sums;
    for (int x = 0; x < L.w; ++x) {
      cand.clear();
      for (int cy = 2 * y; cy < std::min(2 * y + 2, child_h); ++cy)
        for (int cx = 2 * x; cx < std::min(2 * x + 2, child_w); ++cx)
          child_candidates(cx, cy, cand);
      merge_cell(cand, channels, tol, out, sums);
    }
  });
  L.begin.assign(size_t(L.w) * L.h + 1, 0);
  size_t cell = 0;
  for (const RowClusters& r : rows) {
    for (uint32_t c : r.count) {
      L.begin[cell + 1] = L.begin[cell] + c;
      ++cell;
    }
    L.lo.insert(L.lo.end(), r.lo.begin(), r.lo.end());
    L.hi.insert(L.hi.end(), r.hi.begin(), r.hi.end());
    L.n.insert(L.n.end(), r.n.begin(), r.n.end());
    L.nv.insert(L.nv.end(), r.nv.begin(), r.nv.end());
    L.mean.insert(L.mean.end(), r.mean.begin(), r.mean.end());
  }
  L.fill.assign(L.clusters() * size_t(channels), 0.f);
  L.has_fill.assign(L.clusters(), 0);
  return L;
}

// P for a child cell (cx, cy) with depth interval [a, b]: the bilinear interpolation of the
// depth-matching filled clusters of the 4 nearest cells of `parent`. False when none matches.
bool interpolate_parent(const Level& parent, int cx, int cy, float a, float b, int channels,
                        float tol, double* out) {
  // Child centre (c + 0.5) in parent cell units is c / 2 - 0.25 (centres at p + 0.5).
  const int x0 = (cx - 1) >> 1, y0 = (cy - 1) >> 1;  // arithmetic shift: -1 for c = 0
  const double ax = (cx & 1) ? 0.25 : 0.75, ay = (cy & 1) ? 0.25 : 0.75;
  double wsum = 0;
  for (int c = 0; c < channels; ++c) out[c] = 0;
  for (int k = 0; k < 4; ++k) {
    const int px = x0 + (k & 1), py = y0 + (k >> 1);
    if (px < 0 || px >= parent.w || py < 0 || py >= parent.h) continue;
    const size_t cell = size_t(py) * parent.w + px;
    int64_t best = -1;
    float best_gap = 0;
    for (uint32_t j = parent.begin[cell]; j < parent.begin[cell + 1]; ++j) {
      if (!parent.has_fill[j]) continue;
      const float gap = std::max(0.f, std::max(a, parent.lo[j]) - std::min(b, parent.hi[j]));
      if (!(gap <= tol * std::min(b, parent.hi[j]))) continue;
      if (best < 0 || gap < best_gap) best = j, best_gap = gap;
    }
    if (best < 0) continue;
    const double w = ((k & 1) ? ax : 1 - ax) * ((k >> 1) ? ay : 1 - ay);
    wsum += w;
    const float* f = &parent.fill[size_t(best) * channels];
    for (int c = 0; c < channels; ++c) out[c] += w * double(f[c]);
  }
  if (!(wsum > 0)) return false;
  for (int c = 0; c < channels; ++c) out[c] /= wsum;
  return true;
}

}  // namespace

std::vector<float> push_pull(int width, int height, int channels, const std::vector<float>& value,
                             const std::vector<uint8_t>& valid, const std::vector<float>& depth,
                             float depth_tolerance, std::vector<uint8_t>* filled) {
  if (width < 0 || height < 0 || channels < 1)
    throw Error(Exit::failure, "push_pull: bad size " + std::to_string(width) + "x" +
                                   std::to_string(height) + "x" + std::to_string(channels));
  const size_t np = size_t(width) * size_t(height);
  if (value.size() != np * size_t(channels) || valid.size() != np || depth.size() != np)
    throw Error(Exit::failure, "push_pull: value, valid or depth does not match " +
                                   std::to_string(width) + "x" + std::to_string(height) + "x" +
                                   std::to_string(channels));
  const float tol = std::max(0.f, depth_tolerance);
  std::vector<float> out(np * size_t(channels), 0.f);
  if (filled) filled->assign(np, 0);
  if (np == 0) return out;

  // Pull. Level 1 from the pixels, then up to a single cell.
  std::vector<Level> levels;
  if (width > 1 || height > 1) {
    levels.push_back(
        pull(width, height, channels, tol, [&](int cx, int cy, std::vector<Candidate>& cand) {
          const size_t i = size_t(cy) * width + cx;
          if (is_background_depth(depth[i])) return;
          const bool v = valid[i] != 0;
          cand.push_back({depth[i], depth[i], 1u, v ? 1u : 0u, v ? &value[i * channels] : nullptr,
                          int(cand.size())});
        }));
    while (levels.back().w > 1 || levels.back().h > 1) {
      const Level& c = levels.back();
      Level next = pull(c.w, c.h, channels, tol, [&](int cx, int cy, std::vector<Candidate>& cand) {
        const size_t cell = size_t(cy) * c.w + cx;
        for (uint32_t j = c.begin[cell]; j < c.begin[cell + 1]; ++j)
          cand.push_back({c.lo[j], c.hi[j], c.n[j], c.nv[j],
                          c.nv[j] > 0 ? &c.mean[size_t(j) * channels] : nullptr, int(cand.size())});
      });
      levels.push_back(std::move(next));
    }
  }

  // Push. The top cell's clusters are their own means; below, blend with the parents.
  if (!levels.empty()) {
    Level& top = levels.back();
    for (size_t j = 0; j < top.clusters(); ++j)
      if (top.nv[j] > 0) {
        top.has_fill[j] = 1;
        std::copy_n(&top.mean[j * channels], channels, &top.fill[j * channels]);
      }
  }
  for (int l = int(levels.size()) - 2; l >= 0; --l) {
    Level& L = levels[size_t(l)];
    const Level& parent = levels[size_t(l) + 1];
    tbb::parallel_for(0, L.h, [&](int y) {
      std::vector<double> p(static_cast<size_t>(channels));
      for (int x = 0; x < L.w; ++x) {
        const size_t cell = size_t(y) * L.w + x;
        for (uint32_t j = L.begin[cell]; j < L.begin[cell + 1]; ++j) {
          const float* m = &L.mean[size_t(j) * channels];
          float* f = &L.fill[size_t(j) * channels];
          const bool have_p = L.nv[j] < L.n[j] && interpolate_parent(parent, x, y, L.lo[j], L.hi[j],
                                                                     channels, tol, p.data());
          if (have_p) {
            const double alpha = double(L.nv[j]) / double(L.n[j]);
            for (int c = 0; c < channels; ++c) f[c] = float(alpha * m[c] + (1 - alpha) * p[c]);
            L.has_fill[j] = 1;
          } else if (L.nv[j] > 0) {
            std::copy_n(m, channels, f);
            L.has_fill[j] = 1;
          }
        }
      }
    });
  }

  // Level 0: copy the valid pixels, fill the holes from level 1.
  tbb::parallel_for(0, height, [&](int y) {
    std::vector<double> p(static_cast<size_t>(channels));
    for (int x = 0; x < width; ++x) {
      const size_t i = size_t(y) * width + x;
      if (valid[i]) {
        std::copy_n(&value[i * channels], channels, &out[i * channels]);
        continue;
      }
      if (is_background_depth(depth[i]) || levels.empty()) continue;
      if (!interpolate_parent(levels[0], x, y, depth[i], depth[i], channels, tol, p.data()))
        continue;
      for (int c = 0; c < channels; ++c) out[i * channels + c] = float(p[c]);
      if (filled) (*filled)[i] = 1;
    }
  });
  return out;
}

}  // namespace hbil
