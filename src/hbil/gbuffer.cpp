// gbuffer.cpp: G-buffer to view space.
#include "hbil/gbuffer.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

namespace hbil {

float half_to_float(std::uint16_t h) {
  const std::uint32_t sign = std::uint32_t(h & 0x8000u) << 16, exp = (h >> 10) & 0x1fu,
                      man = h & 0x3ffu;
  std::uint32_t bits;
  if (exp == 0) {  // zero or subnormal: man × 2^-24, exact in a float
    const float f = float(man) * 0x1p-24f;
    return sign ? -f : f;
  }
  if (exp == 31)
    bits = sign | 0x7f800000u | (man << 13);  // infinity, NaN
  else
    bits = sign | ((exp + 112u) << 23) | (man << 13);
  float f;
  std::memcpy(&f, &bits, 4);
  return f;
}

bool GBuffer::packable(const std::string& field) {
  for (const char* f : {"diffcol", "diffdir", "emit", "env", "glosscol", "glossdir", "glossind",
                        "transcol", "transdir", "transind"})
    if (field == f) return true;
  return false;
}

void GBuffer::unpack() {
  if (packed.empty()) return;
  // Every half's float, from one table (256 KB) built once.
  static const std::vector<float> table = [] {
    std::vector<float> t(65536);
    for (size_t b = 0; b < t.size(); ++b) t[b] = half_to_float(std::uint16_t(b));
    return t;
  }();
  for (auto& entry : packed) {
    std::vector<std::uint16_t>& bits = entry.second;  // not a structured binding: clang 14
    std::vector<Vec3>& v = *rgb(entry.first);         // cannot capture one in a lambda
    v.resize(bits.size() / 3);
    tbb::parallel_for(size_t(0), v.size(), size_t(4096), [&](size_t i0) {
      for (size_t i = i0; i < std::min(v.size(), i0 + 4096); ++i)
        v[i] = Vec3{table[bits[3 * i]], table[bits[3 * i + 1]], table[bits[3 * i + 2]]};
    });
    std::vector<std::uint16_t>().swap(bits);
  }
  packed.clear();
}

bool GBuffer::has(const std::string& field) const {
  for (const auto& entry : packed)
    if (entry.first == field) return true;
  const std::vector<Vec3>* v = const_cast<GBuffer*>(this)->rgb(field);
  return v && !v->empty();
}

std::vector<Vec3>* GBuffer::rgb(const std::string& field) {
  if (field == "normal") return &normal;
  if (field == "position") return &position;
  if (field == "diffcol") return &diffcol;
  if (field == "diffdir") return &diffdir;
  if (field == "emit") return &emit;
  if (field == "f0") return &f0;
  if (field == "env") return &env;
  if (field == "glosscol") return &glosscol;
  if (field == "glossdir") return &glossdir;
  if (field == "glossind") return &glossind;
  if (field == "transcol") return &transcol;
  if (field == "transdir") return &transdir;
  if (field == "transind") return &transind;
  return nullptr;
}

namespace {

bool covered(const GBuffer& g, const Params& p, size_t i) {
  if (!g.alpha.empty() && !(g.alpha[i] > 0.f)) return false;
  if (!g.depth.empty()) return g.depth[i] < p.background_depth;
  const Vec3& w = g.position[i];
  return !(w.x == 0 && w.y == 0 && w.z == 0);  // Blender background
}

}  // namespace

ZeroNormals find_zero_normals(const GBuffer& g, const Params& p) {
  ZeroNormals z;
  if (g.normal.size() != g.pixels() || (g.depth.empty() && g.position.size() != g.pixels()))
    return z;
  for (size_t i = 0; i < g.pixels(); ++i) {
    const Vec3& n = g.normal[i];
    if (n.x == 0 && n.y == 0 && n.z == 0 && covered(g, p, i)) {
      if (z.count == 0) z.first = i;
      ++z.count;
    }
  }
  return z;
}

ViewGBuffer make_view_gbuffer(const GBuffer& g, const Camera& cam, const Params& p) {
  ViewGBuffer v;
  v.width = g.width;
  v.height = g.height;
  v.position.assign(g.pixels(), Vec3{0, 0, ViewGBuffer::kBackground});
  v.normal.assign(g.pixels(), Vec3{});
  const bool from_depth = !g.depth.empty();
  const bool back = !g.backdepth.empty();
  if (back) v.thickness.assign(g.pixels(), -1.f);
  tbb::parallel_for(0, g.height, [&](int y) {
    const int simd =
        from_depth && p.vectorised ? view_row_from_depth(g, cam, p.background_depth, y, v) : 0;
    for (int x = simd; x < g.width; ++x) {
      const size_t i = size_t(y) * g.width + x;
      if (!g.alpha.empty() && !(g.alpha[i] > 0.f)) continue;
      const Vec3d n = normalize_or_zero(cam.world_dir_to_view(Vec3d(g.normal[i])));
      if (n.x == 0 && n.y == 0 && n.z == 0) continue;
      Vec3d pv;
      if (from_depth) {
        if (!(g.depth[i] < p.background_depth)) continue;
        pv = cam.unproject(x + 0.5, y + 0.5, g.depth[i]);
      } else {
        const Vec3& w = g.position[i];
        if (w.x == 0 && w.y == 0 && w.z == 0) continue;  // Blender background
        pv = cam.world_to_view(Vec3d(w));
        if (!(pv.z > 0) || !(pv.z < p.background_depth)) continue;
      }
      v.position[i] = Vec3(pv);
      v.normal[i] = Vec3(n);
      if (back) {
        const double zb = g.backdepth[i], zf = pv.z;
        if (zb < p.background_depth && zb > zf * 1.001)
          v.thickness[i] = float(length(pv) * (zb - zf) / zf);
      }
    }
  });
  if (!back && p.thickness_extent && p.method == "bitmask")
    thickness_from_extent(v, cam, float(p.depth_tolerance), float(p.thickness));
  return v;
}

void thickness_from_extent(ViewGBuffer& v, const Camera& cam, float depth_tolerance,
                           float at_most) {
  const int w = v.width, h = v.height;
  const size_t n = v.pixels();
  // Run lengths of the surface through each pixel along its row and its column: neighbours
  // continue the run while they lie within depth_tolerance x depth of its tangent plane
  // (the spatial filter's test, without the normal's: a box's faces are one object); a run
  // that reaches the image's edge has no known end (infinite).
  constexpr float kOpen = HUGE_VALF;
  std::vector<float> across(n, 0.f), down(n, 0.f);
  auto runs = [&](int lines, int length, auto at, std::vector<float>& out) {
    tbb::parallel_for(0, lines, [&](int line) {
      int start = 0;
      for (int k = 1; k <= length; ++k) {
        const size_t a = at(line, k - 1);
        bool joined = false;
        if (k < length && !v.is_background(a)) {
          const size_t b = at(line, k);
          joined =
              !v.is_background(b) && std::fabs(dot(v.position[b] - v.position[a], v.normal[a])) <=
                                         depth_tolerance * v.position[a].z;
        }
        if (joined) continue;
        const bool open = start == 0 || k == length;
        for (int q = start; q < k; ++q) out[at(line, q)] = open ? kOpen : float(k - start);
        start = k;
      }
    });
  };
  runs(
      h, w, [w](int y, int x) { return size_t(y) * size_t(w) + size_t(x); }, across);
  runs(
      w, h, [w](int x, int y) { return size_t(y) * size_t(w) + size_t(x); }, down);
  const float pixel = 2.f / float(cam.fx + cam.fy);  // world size of a pixel per unit depth
  v.thickness.assign(n, -1.f);
  for (size_t i = 0; i < n; ++i) {
    if (v.is_background(i)) continue;
    const float extent = std::min(across[i], down[i]);
    if (extent < kOpen) v.thickness[i] = std::min(extent * pixel * v.position[i].z, at_most);
  }
}

}  // namespace hbil
