// ao_frame.cpp: see ao_frame.h.
#include "hbil/ao_frame.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>

#include "hbil/error.h"
#include "hbil/interleave.h"
#include "hbil/multibounce.h"
#include "hbil/reduced.h"
#include "hbil/spatial_filter.h"
#include "hbil/unseen.h"

namespace hbil {

std::vector<Vec3> source_radiance(const GBuffer& g, const std::vector<Vec3>& irradiance) {
  std::vector<Vec3> L(g.pixels());
  for (size_t i = 0; i < g.pixels(); ++i) {
    L[i] = g.outgoing(i, irradiance.empty() ? g.diffdir[i] : g.diffdir[i] + irradiance[i]);
  }
  return L;
}

Vec3 diffuse_weight(const GBuffer& g, size_t i) {
  if (!g.f0.empty()) {
    const Vec3& f = g.f0[i];
    return {1.f - std::clamp(f.x, 0.f, 1.f), 1.f - std::clamp(f.y, 0.f, 1.f),
            1.f - std::clamp(f.z, 0.f, 1.f)};
  }
  if (!g.metallic.empty()) {
    const float w = 0.96f * (1.f - std::clamp(g.metallic[i], 0.f, 1.f));
    return {w, w, w};
  }
  return {1.f, 1.f, 1.f};
}

void weigh_diffuse(const GBuffer& g, std::vector<Vec3>& e) {
  if (g.f0.empty() && g.metallic.empty()) return;
  tbb::parallel_for(size_t(0), e.size(), [&](size_t i) {
    const Vec3 w = diffuse_weight(g, i);
    e[i] = Vec3{w.x * e[i].x, w.y * e[i].y, w.z * e[i].z};
  });
}

AoFrame compute_ao_frame(const GBuffer& g, const Camera& cam, const Params& p,
                         const SH9* environment, const RadianceCache* cache, int frame,
                         const FillTiles* tiles) {
  return compute_ao_frame(make_view_gbuffer(g, cam, p), g, cam, p, environment, cache, frame,
                          tiles);
}

Params resolve_frame_outputs(const GBuffer& g, const Params& requested) {
  return resolve_outputs(requested, [&g](const std::string& o) {
    return o == "ao" || o == "bentcone" || (g.has("diffcol") && g.has("diffdir"));
  });
}

bool gathers(const Params& p) {
  return p.wants("irradiance") || p.wants("indirect") || p.wants("composite");
}

AoFrame compute_ao_frame(const ViewGBuffer& v, const GBuffer& g, const Camera& cam,
                         const Params& requested, const SH9* environment,
                         const RadianceCache* cache, int frame, const FillTiles* tiles) {
  const Params p = resolve_frame_outputs(g, requested);
  FrameInputs in;
  in.cache = cache;
  in.frame = frame;
  in.tiles = tiles;
  return assemble_frame(v, g, cam, p, search_frame(v, g, cam, p, std::move(in)), environment);
}

Vec3 mean_direct_radiance(const ViewGBuffer& v, const GBuffer& g) {
  // In rows (summed in double, then row sums in order): the same for any thread count.
  std::vector<Vec3d> rows(size_t(v.height));
  std::vector<size_t> counts(size_t(v.height), 0);
  tbb::parallel_for(0, v.height, [&](int y) {
    Vec3d sum;
    size_t n = 0;
    for (int x = 0; x < v.width; ++x) {
      const size_t i = size_t(y) * v.width + x;
      if (v.is_background(i)) continue;
      const Vec3 &a = g.diffcol[i], &e = g.diffdir[i];
      sum += Vec3d(Vec3{a.x * e.x, a.y * e.y, a.z * e.z});  // as source_radiance
      if (!g.emit.empty()) sum += Vec3d(g.emit[i]);
      ++n;
    }
    rows[size_t(y)] = sum;
    counts[size_t(y)] = n;
  });
  Vec3d sum;
  size_t n = 0;
  for (int y = 0; y < v.height; ++y) sum += rows[size_t(y)], n += counts[size_t(y)];
  return n ? Vec3(sum / double(n)) : Vec3{};
}

namespace {

// What the search leaves unblocked within its reach at each pixel of sv, for the escape pass's
// fill (unseen.h, escape_fill_map): the ao of a search of every kReach-th pixel of every
// kReach-th row of sv without the gather's steps, with 2 slices interleaved (1/16 of the
// texels, about 1/30 of the frame's search), or the frame's own slices when it marches every
// direction at every pixel (interleave false, the reference runs); upsampled as a reduced
// search is (reduced.h).
constexpr int kReach = 4;
std::vector<float> search_reach(const ViewGBuffer& sv, const HorizonConfig& c, const Params& p) {
  const ViewGBuffer lo = reduce_view(sv, kReach);
  const float tol = float(p.depth_tolerance);
  HorizonConfig ao_only = c;
  ao_only.gather_steps = 0;
  HorizonImage h =
      p.interleave ? horizon_interleaved(lo, ao_only, 2) : horizon_full(lo, ao_only, p.slices);
  if (p.interleave && p.spatial_filter) h = spatial_filter(lo, h, tol, p.vectorised);
  return std::move(upsample_horizon(sv, lo, kReach, h, tol).ao);
}

}  // namespace

HorizonImage search_frame(const ViewGBuffer& v, const GBuffer& g, const Camera& cam,
                          const Params& p, FrameInputs in) {
  HorizonConfig c = make_horizon_config(p, cam);
  if (in.rotate)
    frame_rotation(in.frame, p.interleave ? 16 * p.slices : p.slices, c.rotation, c.jitter_shift);
  const bool gather = gathers(p);
  // Later bounces sum the first one's recorded gather with their radiance instead of
  // marching again (interleaved bitmask search; identical results), and so does every search
  // with in.record once it is filled.
  GatherRecord record;
  GatherRecord* reuse = !gather         ? nullptr
                        : in.record     ? in.record
                        : p.bounces > 1 ? &record
                                        : nullptr;
  // A reduced search (search_scale > 1) marches every f-th pixel of every f-th row and its
  // result is upsampled to v (reduced.h).
  const int f = effective_search_scale(p, v.width, v.height);
  const float tol = float(p.depth_tolerance);
  ViewGBuffer own_lo;
  if (f > 1 && !in.reduced) own_lo = reduce_view(v, f);
  const ViewGBuffer& lo = in.reduced ? *in.reduced : own_lo;
  const ViewGBuffer& sv = f > 1 ? lo : v;
  const bool keep_reduced = in.keep_reduced && f > 1;
  UpsamplePlan own_plan;  // with later bounces (f > 1): which texels each pixel takes
  const UpsamplePlan* plan = in.plan;
  // `radiance` (or null) is released once the search has what it reads of it.
  // `irradiance_only`: a later bounce, whose occlusion is the first's; only its irradiance is
  // filtered (and upsampled).
  auto search = [&](std::vector<Vec3>* radiance, bool irradiance_only) {
    std::vector<Vec3> reduced;
    if (f > 1 && radiance) {
      reduced = reduce_radiance(v, lo, f, *radiance, tol);
      std::vector<Vec3>().swap(*radiance);
      radiance = &reduced;
    }
    HorizonImage h =
        p.interleave ? horizon_interleaved(sv, c, p.slices, radiance, true, reuse, irradiance_only)
                     : horizon_full(sv, c, p.slices, radiance);
    if (irradiance_only) {
      std::vector<float>().swap(h.ao);
      std::vector<float>().swap(h.vis);
      std::vector<Vec3>().swap(h.bent);
    }
    if (p.interleave && p.spatial_filter) h = spatial_filter(sv, h, tol, p.vectorised);
    return h;
  };
  auto upsample = [&](HorizonImage h) {
    if (f == 1) return h;
    // The texels each pixel takes are the same for every bounce: decided once.
    if (!plan && gather && p.bounces > 1) plan = &(own_plan = plan_upsample(v, lo, f, tol));
    return plan ? upsample_horizon(v, lo, *plan, h) : upsample_horizon(v, lo, f, h, tol);
  };
  // Bounce k gathers the outgoing radiance of bounce k − 1 (bounce 0: direct light and
  // Emit where the gather takes it, plus the previous frame's indirect light when the temporal
  // chain feeds it back). Occlusion is the same every time: the first search's is kept, and the
  // later bounces filter and upsample their irradiance alone. Each buffer
  // is released at its last use: the feedback and the previous bounce once the source radiance is
  // made, the source radiance once the march has what it reads.
  HorizonImage h;
  // unseen_radiance "auto": a fraction of the frame's mean direct outgoing radiance, times
  // what does not escape over each pixel's hemisphere (unseen.h), the same for every bounce.
  // With the radiance cache or a panorama, its fill per searched pixel, with unseen_radiance
  // where it knows nothing: with "auto" each pixel's own fill (so that it changes only what it
  // knows).
  const bool cached = gather && in.cache && !in.cache->empty();
  // unseen_scale multiplies either (the fill's level; calibration solves it per shot).
  const float u = float(p.unseen_radiance * p.unseen_scale);
  std::vector<Vec3> fill_map;
  if (gather) c.fill = Vec3{u, u, u};
  if (gather && p.unseen_radiance_auto) {
    const bool escape_pass = !g.escape.empty();
    c.fill = mean_direct_radiance(v, g) *
             (auto_unseen_factor(p.unseen_carry || escape_pass) * float(p.unseen_scale));
    if (escape_pass) {
      // The render says what escapes the scene; the search, what it leaves open (unseen.h).
      fill_map = escape_fill_map(sv, escape_at_view(v, sv, f, g.escape, tol),
                                 search_reach(sv, c, p), c.fill);
      c.fill_map = fill_map.data();
    } else {
      fill_map = unseen_fill_map(sv, escape_profile(v, cam, p.unseen_carry), c.fill);
      c.fill_map = fill_map.data();
    }
  }
  if (gather && in.tiles && !in.tiles->empty()) {
    // The calibrated level of each searched pixel's surface (fill_tiles.h), on the fill it
    // has without a cache, so that what a cache or a panorama knows stays as they show it.
    if (fill_map.empty()) fill_map.assign(sv.pixels(), c.fill);
    tbb::parallel_for(0, sv.height, [&](int y) {
      for (int x = 0; x < sv.width; ++x) {
        const size_t i = size_t(y) * size_t(sv.width) + size_t(x);
        if (sv.is_background(i)) continue;
        fill_map[i] = fill_map[i] * in.tiles->at(cam.view_to_world(Vec3d(sv.position[i])));
      }
    });
    c.fill_map = fill_map.data();
  }
  if (cached && !fill_map.empty()) {  // each pixel's own fill where the cache knows nothing
    fill_map = in.cache->fill_map(sv, cam, in.frame, fill_map);
    c.fill_map = fill_map.data();
  } else if (cached) {
    fill_map = in.cache->fill_map(sv, cam, in.frame, c.fill);
    c.fill_map = fill_map.data();
  }
  const int bounces = gather ? p.bounces : 1;
  HorizonImage occlusion;  // the first bounce's ao, vis and bent, which every bounce shares
  for (int bounce = 0; bounce < bounces; ++bounce) {
    std::vector<Vec3> L;
    if (gather) {
      L = source_radiance(g, bounce == 0 ? in.feedback : h.irradiance);
      std::vector<Vec3>().swap(in.feedback);
      h = HorizonImage{};
    }
    const bool last = bounce + 1 == bounces;
    h = search(gather ? &L : nullptr, bounce > 0);
    // The first bounce's occlusion is kept upsampled, or with keep_reduced on the texels, as
    // the last bounce is.
    auto keep_occlusion = [&] {
      occlusion.ao = std::move(h.ao);
      occlusion.vis = std::move(h.vis);
      occlusion.bent = std::move(h.bent);
    };
    if (keep_reduced && bounce == 0 && bounces > 1) keep_occlusion();
    if (!(keep_reduced && last)) h = upsample(std::move(h));
    if (!keep_reduced && bounce == 0 && bounces > 1) keep_occlusion();
    if (last && bounces > 1) {
      h.ao = std::move(occlusion.ao);
      h.vis = std::move(occlusion.vis);
      h.bent = std::move(occlusion.bent);
    }
    if (!(keep_reduced && last)) weigh_diffuse(g, h.irradiance);
  }
  return h;
}

AoFrame assemble_frame(const ViewGBuffer& v, const GBuffer& g, const Camera& cam, const Params& p,
                       HorizonImage h, const SH9* environment, GBuffer* release) {
  const bool gather = gathers(p);
  const bool far = p.wants("farfield") || (p.wants("composite") && environment);
  if (far && !environment) throw Error(Exit::preset, "output farfield needs an environment");
  const size_t n = v.pixels();
  if (h.ao.size() != n || h.vis.size() != n || h.bent.size() != n ||
      (gather && h.irradiance.size() != n))
    throw Error(Exit::failure, "assemble_frame: the search result does not match the frame");
  // ao, cone_cos, bent and irradiance are computed in place, over h.ao, h.vis, h.bent and
  // h.irradiance: each pixel reads its search values before it writes its outputs.
  AoFrame out;
  out.width = v.width;
  out.height = v.height;
  out.ao = std::move(h.ao);
  out.cone_cos = std::move(h.vis);
  out.bent = std::move(h.bent);
  if (gather) out.irradiance = std::move(h.irradiance);
  // The composite first: the fields only it reads are released (with `release`) before the
  // other outputs take memory.
  const bool composite = p.wants("composite");
  if (composite) {
    if (release) {  // over DiffDir: each pixel reads its DiffDir before it writes
      out.composite = std::move(release->diffdir);
      out.composite_alpha = std::move(release->alpha);
    } else {
      out.composite.resize(n);
      out.composite_alpha = g.alpha;
    }
    const std::vector<Vec3>& diffdir = release ? out.composite : g.diffdir;
    tbb::parallel_for(0, v.height, [&](int y) {
      for (int x = 0; x < v.width; ++x) {
        const size_t i = size_t(y) * v.width + x;
        // composite = DiffCol × (DiffDir + E_near/π [+ E_far/π]) + Emit + Env + glossy +
        // transmission. Every term is a pixel-filtered pass, so the sum is premultiplied.
        Vec3 e = diffdir[i];
        if (!v.is_background(i)) e += out.irradiance[i];
        Vec3 rgb{g.diffcol[i].x * e.x, g.diffcol[i].y * e.y, g.diffcol[i].z * e.z};
        for (const std::vector<Vec3>* add : {&g.emit, &g.env})
          if (!add->empty()) rgb += (*add)[i];
        auto lobe = [&](const std::vector<Vec3>& col, const std::vector<Vec3>& dir,
                        const std::vector<Vec3>& ind) {
          if (col.empty()) return;
          Vec3 l = dir.empty() ? Vec3{} : dir[i];
          if (!ind.empty()) l += ind[i];
          rgb += Vec3{col[i].x * l.x, col[i].y * l.y, col[i].z * l.z};
        };
        lobe(g.glosscol, g.glossdir, g.glossind);
        lobe(g.transcol, g.transdir, g.transind);
        out.composite[i] = rgb;
      }
    });
  }
  if (release) {
    for (std::vector<Vec3>* f :
         {&release->emit, &release->env, &release->glosscol, &release->glossdir, &release->glossind,
          &release->transcol, &release->transdir, &release->transind})
      std::vector<Vec3>().swap(*f);
  }
  if (gather) out.indirect.assign(n, Vec3{});
  const bool multibounce = p.ao_multibounce && p.wants("ao");
  if (multibounce) out.ao_rgb.assign(n, Vec3{1, 1, 1});
  if (far) out.farfield.assign(n, Vec3{});
  const std::vector<Vec3>& world_normal = g.normal;
  tbb::parallel_for(0, v.height, [&](int y) {
    for (int x = 0; x < v.width; ++x) {
      const size_t i = size_t(y) * v.width + x;
      if (v.is_background(i)) {
        out.ao[i] = 1.f;
        out.cone_cos[i] = 0.f;
        out.bent[i] = world_normal.empty() ? Vec3{} : world_normal[i];
        if (gather) out.irradiance[i] = Vec3{};
        continue;
      }
      if (gather) {
        const Vec3 e = out.irradiance[i], a = g.diffcol[i];
        out.indirect[i] = Vec3{a.x * e.x, a.y * e.y, a.z * e.z};
      }
      out.ao[i] = std::clamp(out.ao[i], 0.f, 1.f);
      out.cone_cos[i] = std::clamp(1.f - out.cone_cos[i], 0.f, 1.f);  // eq. 12
      const Vec3 b = Vec3(normalize_or_zero(cam.view_dir_to_world(Vec3d(out.bent[i]))));
      // Fully occluded: no bent direction; fall back to the (unit) normal.
      out.bent[i] =
          dot(b, b) > 0 ? b : Vec3(normalize_or_zero(cam.view_dir_to_world(Vec3d(v.normal[i]))));
      if (multibounce) out.ao_rgb[i] = multibounce_ao(out.ao[i], g.diffcol[i]);
      if (far) {
        // §2.2.4: SH irradiance limited to the bent cone, t = cos α; stored as E/π.
        const Vec3 w = diffuse_weight(g, i),
                   e = cone_irradiance(*environment, out.bent[i], out.cone_cos[i]) / float(M_PI);
        out.farfield[i] = Vec3{w.x * e.x, w.y * e.y, w.z * e.z};
        if (composite) {
          const Vec3 a = g.diffcol[i], f = out.farfield[i];
          Vec3& c = out.composite[i];
          c.x += a.x * f.x;
          c.y += a.y * f.y;
          c.z += a.z * f.z;
        }
      }
    }
  });
  return out;
}

}  // namespace hbil
