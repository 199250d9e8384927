// radiance_cache.cpp: see radiance_cache.h.
#include "hbil/radiance_cache.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>

namespace hbil {

namespace {

constexpr double kPi = 3.14159265358979323846;

// Equirectangular map of view-space directions (+x right, +y down, +z forward): column by
// azimuth atan2(x, z) from -π to π, row by the angle from "up" (-y), 0 at the top row.
void to_map(const Vec3d& d, int w, int h, double& u, double& v) {
  const double len = std::sqrt(dot(d, d));
  const double up = std::clamp(-d.y / len, -1.0, 1.0);
  u = (std::atan2(d.x, d.z) / (2 * kPi) + 0.5) * w;
  v = std::acos(up) / kPi * h;
}
Vec3d from_map(double u, double v, int w, int h) {
  const double phi = (u / w - 0.5) * 2 * kPi, theta = v / h * kPi;
  return {std::sin(theta) * std::sin(phi), -std::cos(theta), std::sin(theta) * std::cos(phi)};
}
bool in_frustum(const Camera& cam, const Vec3d& d) {
  if (!(d.z > 0)) return false;
  double u, v;
  cam.project(d, u, v);
  return u >= 0 && u <= cam.width && v >= 0 && v <= cam.height;
}

}  // namespace

void RadianceCache::append(std::vector<Entry>& to, const ViewGBuffer& v, const Camera& cam,
                           const GBuffer& g, const std::vector<Vec3>* E, int frame) {
  const int s = std::max(1, (v.width + kColumns - 1) / kColumns);
  for (int y = s / 2; y < v.height; y += s)
    for (int x = s / 2; x < v.width; x += s) {
      const size_t i = size_t(y) * v.width + x;
      if (v.is_background(i)) {
        const Vec3d ray = cam.unproject(x + 0.5, y + 0.5, 1.0);
        to.push_back({Vec3(normalize_or_zero(cam.view_dir_to_world(ray))), Vec3{}, frame, true});
      } else {
        const Vec3 l = g.outgoing(i, E ? g.diffdir[i] + (*E)[i] : g.diffdir[i]);
        if (!(std::isfinite(l.x) && std::isfinite(l.y) && std::isfinite(l.z))) continue;
        to.push_back({Vec3(cam.view_to_world(Vec3d(v.position[i]))), l, frame, false});
      }
    }
}

void RadianceCache::add(const ViewGBuffer& v, const Camera& cam, const GBuffer& g,
                        const std::vector<Vec3>& E, int frame) {
  // Entries no later frame reads (frame + 1 reads from frame + 1 - frames_ on), and this
  // frame's entries ahead, replaced by what it output.
  const int oldest = frame + 1 - frames_;
  entries_.erase(std::remove_if(entries_.begin(), entries_.end(),
                                [&](const Entry& e) { return e.frame < oldest; }),
                 entries_.end());
  ahead_.erase(std::remove_if(ahead_.begin(), ahead_.end(),
                              [&](const Entry& e) { return e.frame <= frame; }),
               ahead_.end());
  cuts_.erase(std::remove_if(cuts_.begin(), cuts_.end(), [&](int c) { return c <= frame; }),
              cuts_.end());
  if (frames_ > 0) append(entries_, v, cam, g, &E, frame);
}

void RadianceCache::add_ahead(const ViewGBuffer& v, const Camera& cam, const GBuffer& g, int frame,
                              bool cut) {
  if (cut) cuts_.push_back(frame);
  append(ahead_, v, cam, g, nullptr, frame);
}

bool RadianceCache::reads_ahead(int frame, int ahead) const {
  if (!(ahead > frame && ahead <= frame + ahead_frames_)) return false;
  for (int c : cuts_)
    if (c > frame && c <= ahead) return false;
  return true;
}

Vec3 RadianceCache::panorama_ambient(const GBuffer& pano, float background) {
  // Solid-angle weighted means over the whole sphere (rows of an equirectangular image
  // weigh sin θ); the background counts with no albedo and no radiance.
  Vec3d direct{0, 0, 0}, albedo{0, 0, 0};
  double all = 0;
  for (int y = 0; y < pano.height; ++y) {
    const double w = std::sin((y + 0.5) * kPi / pano.height);
    for (int x = 0; x < pano.width; ++x) {
      const size_t i = size_t(y) * pano.width + x;
      all += w;
      if (!(pano.depth[i] < background)) continue;
      direct = direct + Vec3d(pano.outgoing(i, pano.diffdir[i])) * w;
      albedo = albedo + Vec3d(pano.diffcol[i]) * w;
    }
  }
  if (!(all > 0)) return {};
  auto channel = [&](double d, double a) {
    return float(d / all / (1 - std::clamp(a / all, 0.0, kMaxAmbientAlbedo)));
  };
  return {channel(direct.x, albedo.x), channel(direct.y, albedo.y), channel(direct.z, albedo.z)};
}

void RadianceCache::set_panorama(const GBuffer& pano, float background, int frame) {
  panorama_.clear();
  const Vec3 ambient = panorama_ambient(pano, background);
  const int s = std::max(1, (pano.width + kPanoramaColumns - 1) / kPanoramaColumns);
  for (int y = s / 2; y < pano.height; y += s)
    for (int x = s / 2; x < pano.width; x += s) {
      const size_t i = size_t(y) * pano.width + x;
      if (!(pano.depth[i] < background)) continue;
      const Vec3 l = pano.outgoing(i, pano.diffdir[i] + ambient);
      if (!(std::isfinite(l.x) && std::isfinite(l.y) && std::isfinite(l.z))) continue;
      panorama_.push_back({pano.position[i], l, frame, false});
    }
}

RadianceCache::Sums RadianceCache::fill_sums(const Camera& cam, int frame) const {
  constexpr int W = kProbeWidth, H = kProbeHeight, n_tex = W * H;
  // 1. The probe: nearest distance per texel, then the mean of the entries within the band.
  // The earlier frames' entries, those ahead, then the panorama's.
  const size_t n_past = entries_.size(), n_frames = n_past + ahead_.size(),
               n = n_frames + panorama_.size();
  auto entry = [&](size_t k) -> const Entry& {
    return k < n_past ? entries_[k] : k < n_frames ? ahead_[k - n_past] : panorama_[k - n_frames];
  };
  std::vector<float> nearest(n_tex, HUGE_VALF);
  std::vector<int> texel(n, -1);
  std::vector<float> dist(n, HUGE_VALF);
  std::vector<unsigned char> sky(n_tex, 0);
  for (size_t k = 0; k < n; ++k) {
    const Entry& e = entry(k);
    const bool readable = k < n_past     ? e.frame < frame && e.frame >= frame - frames_
                          : k < n_frames ? reads_ahead(frame, e.frame)
                                         : e.frame == frame;
    if (!readable) continue;
    const Vec3d d = e.sky ? cam.world_dir_to_view(Vec3d(e.p)) : cam.world_to_view(Vec3d(e.p));
    const double len = std::sqrt(dot(d, d));
    // What the frame shows now is searched on screen (and keeps a static camera's fill); the
    // panorama also holds what lies beyond the gather's reach there.
    const bool panorama = k >= n_frames;
    if (!(len > 0) || (!panorama && in_frustum(cam, d))) continue;
    double u, v;
    to_map(d, W, H, u, v);
    const int tx = std::clamp(int(u), 0, W - 1), ty = std::clamp(int(v), 0, H - 1);
    texel[k] = ty * W + tx;
    if (e.sky) {
      sky[texel[k]] = 1;
    } else {
      dist[k] = float(len);
      nearest[texel[k]] = std::min(nearest[texel[k]], dist[k]);
    }
  }
  std::vector<Vec3> sum(n_tex);
  std::vector<int> count(n_tex, 0);
  std::vector<unsigned char> seen_by_panorama(n_tex, 0);
  for (size_t k = 0; k < n; ++k) {
    const int t = texel[k];
    if (t < 0 || entry(k).sky || !(dist[k] <= nearest[t] * (1.f + kDepthBand))) continue;
    sum[t] += entry(k).L;
    seen_by_panorama[t] |= k >= n_frames;
    ++count[t];
  }
  // Texel directions, solid angles and whether the frustum holds them.
  struct Texel {
    Vec3d d;
    double omega;
    bool used;  // off screen, or on screen where the panorama has its surface
    int state;  // 0 unknown, 1 known
    Vec3 L;
  };
  std::vector<Texel> tex(n_tex);
  for (int ty = 0; ty < H; ++ty) {
    const double omega = (2 * kPi / W) * (std::cos(ty * kPi / H) - std::cos((ty + 1) * kPi / H));
    for (int tx = 0; tx < W; ++tx) {
      Texel& t = tex[ty * W + tx];
      const int i = ty * W + tx;
      t.d = from_map(tx + 0.5, ty + 0.5, W, H);
      t.omega = omega;
      t.used = !in_frustum(cam, t.d) || seen_by_panorama[i];
      t.state = count[i] > 0 || sky[i] ? 1 : 0;
      t.L = count[i] > 0 ? sum[i] * (1.f / float(count[i])) : Vec3{};
    }
  }
  // 2. The sums per normal.
  const size_t n_table = size_t(kTableWidth) * kTableHeight;
  Sums sums{std::vector<Vec3d>(n_table), std::vector<double>(n_table),
            std::vector<double>(n_table)};
  const double eps = kEpsilon * kPi;
  tbb::parallel_for(0, kTableHeight, [&](int ny) {
    for (int nx = 0; nx < kTableWidth; ++nx) {
      const Vec3d n = from_map(nx + 0.5, ny + 0.5, kTableWidth, kTableHeight);
      Vec3d known{0, 0, 0};
      double unknown = 0, all = 0;
      for (const Texel& t : tex) {
        if (!t.used) continue;
        const double c = dot(n, t.d);
        if (!(c > 0)) continue;
        const double w = c * t.omega;
        all += w;
        if (t.state)
          known = known + Vec3d(t.L) * w;
        else
          unknown += w;
      }
      const size_t k = size_t(ny) * kTableWidth + nx;
      sums.known[k] = known;
      sums.unknown[k] = unknown + eps;
      sums.all[k] = all + eps;
    }
  });
  return sums;
}

std::vector<Vec3> RadianceCache::fill_table(const Camera& cam, int frame, Vec3 fallback) const {
  const Sums s = fill_sums(cam, frame);
  std::vector<Vec3> table(s.known.size());
  const Vec3d fb(fallback);
  for (size_t k = 0; k < table.size(); ++k)
    table[k] = Vec3((s.known[k] + fb * s.unknown[k]) * (1.0 / s.all[k]));
  return table;
}

Vec3 RadianceCache::lookup(const std::vector<Vec3>& table, const Vec3& n) {
  double u, v;
  to_map(Vec3d(n), kTableWidth, kTableHeight, u, v);
  u -= 0.5, v -= 0.5;
  const double fu = std::floor(u), fv = std::floor(v);
  const double au = u - fu, av = v - fv;
  const int x0 = int(fu), y0 = int(fv);
  auto at = [&](int x, int y) {
    x = ((x % kTableWidth) + kTableWidth) % kTableWidth;
    y = std::clamp(y, 0, kTableHeight - 1);
    return Vec3d(table[size_t(y) * kTableWidth + x]);
  };
  const Vec3d r = (at(x0, y0) * (1 - au) + at(x0 + 1, y0) * au) * (1 - av) +
                  (at(x0, y0 + 1) * (1 - au) + at(x0 + 1, y0 + 1) * au) * av;
  return Vec3(r);
}

std::vector<Vec3> RadianceCache::fill_map(const ViewGBuffer& v, const Camera& cam, int frame,
                                          const std::vector<Vec3>& fallback) const {
  // Two tables: the known part, and the unknown share (the same in every channel).
  const Sums s = fill_sums(cam, frame);
  std::vector<Vec3> known(s.known.size()), unknown(s.known.size());
  for (size_t k = 0; k < known.size(); ++k) {
    known[k] = Vec3(s.known[k] * (1.0 / s.all[k]));
    const float u = float(s.unknown[k] / s.all[k]);
    unknown[k] = Vec3{u, u, u};
  }
  std::vector<Vec3> fill(v.pixels());
  tbb::parallel_for(0, v.height, [&](int y) {
    for (int x = 0; x < v.width; ++x) {
      const size_t i = size_t(y) * v.width + x;
      if (v.is_background(i)) continue;
      const float u = lookup(unknown, v.normal[i]).x;
      fill[i] = lookup(known, v.normal[i]) + fallback[i] * u;
    }
  });
  return fill;
}

std::vector<Vec3> RadianceCache::fill_map(const ViewGBuffer& v, const Camera& cam, int frame,
                                          Vec3 fallback) const {
  const std::vector<Vec3> table = fill_table(cam, frame, fallback);
  std::vector<Vec3> fill(v.pixels());
  tbb::parallel_for(0, v.height, [&](int y) {
    for (int x = 0; x < v.width; ++x) {
      const size_t i = size_t(y) * v.width + x;
      if (!v.is_background(i)) fill[i] = lookup(table, v.normal[i]);
    }
  });
  return fill;
}

}  // namespace hbil
