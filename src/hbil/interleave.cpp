// interleave.cpp: see interleave.h.
#include "hbil/interleave.h"

#include <tbb/parallel_for.h>

#include <numbers>

#include "hbil/march.h"

namespace hbil {

namespace {

constexpr float kPi = std::numbers::pi_v<float>;
// 4x4 ordered-dither (Bayer) matrix: adjacent pixels get rotations far apart.
constexpr int kBayer4[16] = {0, 8, 2, 10, 12, 4, 14, 6, 3, 11, 1, 9, 15, 7, 13, 5};

void store(HorizonImage& out, size_t idx, const PixelSums& s, int n_slices) {
  out.ao[idx] = s.ao / float(n_slices);
  out.vis[idx] = s.vis / float(2 * n_slices);
  out.bent[idx] = s.bent / float(n_slices);
  if (!out.irradiance.empty()) out.irradiance[idx] = s.irradiance / float(n_slices);
}

// A jitter in (0, 1) shifted by s, mod 1 (s = 0: unchanged).
float shifted(float jitter, float s) {
  const float j = jitter + s;
  return j >= 1.f ? j - 1.f : j;
}

}  // namespace

HorizonImage unoccluded_image(const ViewGBuffer& g, bool gather) {
  HorizonImage out;
  out.width = g.width;
  out.height = g.height;
  out.ao.assign(g.pixels(), 1.f);
  out.vis.assign(g.pixels(), 1.f);
  out.bent.assign(g.pixels(), Vec3{});
  if (gather) out.irradiance.assign(g.pixels(), Vec3{});
  return out;
}

void interleaved_angles(int phase, int slices, float* phi) {
  for (int s = 0; s < slices; ++s)
    phi[s] = kPi * (float(16 * s + kBayer4[phase]) + 0.5f) / float(16 * slices);
}

float interleaved_jitter(int phase) {
  const int transposed = (phase % 4) * 4 + phase / 4;
  return (float(kBayer4[transposed]) + 0.5f) / 16.f;
}

HorizonImage horizon_full(const ViewGBuffer& g, const HorizonConfig& c, int slices,
                          const std::vector<Vec3>* radiance) {
  HorizonImage out = unoccluded_image(g, radiance != nullptr);
  std::vector<float> phi(slices);
  for (int s = 0; s < slices; ++s) phi[s] = kPi * (float(s) + 0.5f) / float(slices) + c.rotation;
  const std::vector<float> fraction = step_fractions(c, shifted(0.5f, c.jitter_shift));
  const std::vector<std::uint64_t> surface =
      c.vectorised ? texel_surfaces(g.position.data(), g.normal.data(), g.pixels())
                   : std::vector<std::uint64_t>{};
  SampleView view{g.position.data(),
                  g.normal.data(),
                  g.width,
                  g.height,
                  1,
                  g.width,
                  g.scale,
                  radiance ? radiance->data() : nullptr,
                  g.thickness.empty() ? nullptr : g.thickness.data(),
                  c.fill_map};
  if (!surface.empty()) view.surface = surface.data();
  tbb::parallel_for(0, g.height, [&](int y) {
    if (c.vectorised) {
      std::vector<PixelSums> row(g.width);
      march_row(view, 0, y, g.width, phi.data(), slices, fraction.data(), c, row.data());
      for (int x = 0; x < g.width; ++x) {
        const size_t i = size_t(y) * g.width + x;
        if (!g.is_background(i)) store(out, i, row[x], slices);
      }
      return;
    }
    for (int x = 0; x < g.width; ++x) {
      const size_t i = size_t(y) * g.width + x;
      if (g.is_background(i)) continue;
      store(out, i,
            march_pixel(view, x, y, g.position[i], g.normal[i], phi.data(), slices, fraction.data(),
                        c),
            slices);
    }
  });
  return out;
}

HorizonImage horizon_interleaved(const ViewGBuffer& g, const HorizonConfig& c, int slices,
                                 const std::vector<Vec3>* radiance, bool copy_subbuffers,
                                 GatherRecord* record, bool irradiance_only) {
  if (!c.bitmask || !radiance) record = nullptr;
  const bool replay = record && record->filled;
  HorizonImage out;
  if (replay && irradiance_only) {
    out.width = record->first.width;
    out.height = record->first.height;
    out.irradiance = record->first.irradiance;
  } else {
    out = replay ? record->first : unoccluded_image(g, radiance != nullptr);
  }
  // Sub-buffer of phase (ox, oy): texel (i, j) is full-resolution pixel (4i + ox, 4j + oy).
  struct Sub {
    int ox, oy, w, h;
    std::vector<Vec3> pos, nrm, rad, fill;  // contiguous copies (empty when reading in place)
    std::vector<float> thick;
    std::vector<std::uint64_t> surface;
    SampleView view;
    std::vector<float> phi;
    std::vector<float> fraction;  // step positions, with this phase's jitter
  };
  std::vector<Sub> subs(16);
  for (int phase = 0; phase < 16; ++phase) {
    Sub& s = subs[phase];
    s.ox = phase % 4;
    s.oy = phase / 4;
    s.w = (g.width - s.ox + 3) / 4;
    s.h = (g.height - s.oy + 3) / 4;
    s.phi.resize(slices);
    interleaved_angles(phase, slices, s.phi.data());
    for (float& a : s.phi) a += c.rotation;
    s.fraction = step_fractions(c, shifted(interleaved_jitter(phase), c.jitter_shift));
  }
  // Deinterleave (split depth and normals into the 16 quarter-resolution buffers).
  tbb::parallel_for(0, 16, [&](int phase) {
    Sub& s = subs[phase];
    if (s.w <= 0 || s.h <= 0) return;
    if (copy_subbuffers) {
      s.pos.resize(size_t(s.w) * s.h);
      s.nrm.resize(size_t(s.w) * s.h);
      if (radiance) s.rad.resize(size_t(s.w) * s.h);
      if (!g.thickness.empty()) s.thick.resize(size_t(s.w) * s.h);
      if (c.fill_map) s.fill.resize(size_t(s.w) * s.h);
      for (int j = 0; j < s.h; ++j)
        for (int i = 0; i < s.w; ++i) {
          const size_t src = size_t(4 * j + s.oy) * g.width + (4 * i + s.ox);
          s.pos[size_t(j) * s.w + i] = g.position[src];
          s.nrm[size_t(j) * s.w + i] = g.normal[src];
          if (radiance) s.rad[size_t(j) * s.w + i] = (*radiance)[src];
          if (!s.thick.empty()) s.thick[size_t(j) * s.w + i] = g.thickness[src];
          if (!s.fill.empty()) s.fill[size_t(j) * s.w + i] = c.fill_map[src];
        }
      s.view = SampleView{s.pos.data(),
                          s.nrm.data(),
                          s.w,
                          s.h,
                          1,
                          s.w,
                          4 * g.scale,
                          radiance ? s.rad.data() : nullptr,
                          s.thick.empty() ? nullptr : s.thick.data(),
                          s.fill.empty() ? nullptr : s.fill.data()};
      if (c.vectorised) {
        s.surface = texel_surfaces(s.pos.data(), s.nrm.data(), s.pos.size());
        s.view.surface = s.surface.data();
      }
    } else {
      const size_t first = size_t(s.oy) * g.width + s.ox;
      s.view = SampleView{g.position.data() + first,
                          g.normal.data() + first,
                          s.w,
                          s.h,
                          4,
                          std::ptrdiff_t(4) * g.width,
                          4 * g.scale,
                          radiance ? radiance->data() + first : nullptr,
                          g.thickness.empty() ? nullptr : g.thickness.data() + first,
                          c.fill_map ? c.fill_map + first : nullptr};
    }
  });
  // March every sub-buffer row; write results back to full resolution (re-interleave).
  int rows = 0;
  std::vector<std::pair<int, int>> tasks;  // (phase, row)
  for (int phase = 0; phase < 16; ++phase)
    for (int j = 0; j < subs[phase].h; ++j) tasks.emplace_back(phase, j), ++rows;
  if (record && !replay) record->rows.assign(rows, GatherLog{});
  tbb::parallel_for(0, rows, [&](int task) {
    const auto [phase, j] = tasks[task];
    const Sub& s = subs[phase];
    if (replay) {
      const GatherLog& log = record->rows[task];
      size_t entry = 0, count = 0;
      for (int i = 0; i < s.w; ++i) {
        const size_t dst = size_t(4 * j + s.oy) * g.width + (4 * i + s.ox);
        if (g.is_background(dst)) continue;
        out.irradiance[dst] =
            replay_gather(log, s.view.radiance, s.view.fill_at(c, i, j), slices, entry, count) /
            float(slices);
      }
      return;
    }
    GatherLog* log = record ? &record->rows[task] : nullptr;
    if (c.vectorised) {
      std::vector<PixelSums> row(s.w);
      march_row(s.view, 0, j, s.w, s.phi.data(), slices, s.fraction.data(), c, row.data(), log);
      for (int i = 0; i < s.w; ++i) {
        const size_t dst = size_t(4 * j + s.oy) * g.width + (4 * i + s.ox);
        if (!g.is_background(dst)) store(out, dst, row[i], slices);
      }
      return;
    }
    for (int i = 0; i < s.w; ++i) {
      const size_t dst = size_t(4 * j + s.oy) * g.width + (4 * i + s.ox);
      if (g.is_background(dst)) continue;
      const Vec3& P = copy_subbuffers ? s.pos[size_t(j) * s.w + i] : g.position[dst];
      const Vec3& n = copy_subbuffers ? s.nrm[size_t(j) * s.w + i] : g.normal[dst];
      store(out, dst,
            march_pixel(s.view, i, j, P, n, s.phi.data(), slices, s.fraction.data(), c, log),
            slices);
    }
  });
  if (record && !replay) {
    record->first = out;
    record->filled = true;
  }
  if (irradiance_only && !replay) {
    std::vector<float>().swap(out.ao);
    std::vector<float>().swap(out.vis);
    std::vector<Vec3>().swap(out.bent);
  }
  return out;
}

}  // namespace hbil
