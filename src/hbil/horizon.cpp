// horizon.cpp: see horizon.h for the paper sections and departures.
#include "hbil/horizon.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <numbers>

namespace hbil {

namespace {
constexpr float kPi = std::numbers::pi_v<float>;
inline float sgn(float t) {
  return t < 0.f ? -1.f : 1.f;
}
// Below this |cos| between the sample's normal and the corrected ray the tangent-plane
// correction is unstable (silhouettes, poles seen side-on) and the sample is used as is.
constexpr float kGrazing = 0.1f;
// acos to 7e-5 rad (Abramowitz & Stegun 4.4.45), well under the bitmask's sector width of
// π/32 = 0.098 rad; used for the extents of bitmask occluders.
inline float fast_acos(float x) {
  const float a = std::fabs(x);
  const float r =
      std::sqrt(1.f - a) * (1.5707288f + a * (-0.2121144f + a * (0.0742610f - 0.0187293f * a)));
  return x < 0.f ? kPi - r : r;
}
}  // namespace

HorizonConfig make_horizon_config(const Params& p, const Camera& cam) {
  HorizonConfig c;
  c.radius = float(p.radius);
  c.steps = p.steps;
  c.step_power = float(p.step_power);
  c.fx = float(cam.fx);
  c.fy = float(cam.fy);
  c.bitmask = p.method == "bitmask";
  c.thickness = float(p.thickness);
  c.thickness_growth = float(p.thickness_growth);
  c.gather_radius = float(std::max(p.radius, p.gather_radius));
  c.gather_steps = c.gather_radius > c.radius ? p.gather_steps : 0;
  return c;
}

void frame_rotation(int frame, int directions, float& rotation, float& jitter_shift) {
  // Radical inverse in base 2 of the frame number (bit-reversed), in [0, 1).
  unsigned n = unsigned(frame), r = 0;
  for (int b = 0; b < 32; ++b, n >>= 1) r = (r << 1) | (n & 1u);
  const double vdc = double(r) / 4294967296.0;
  rotation = float(vdc * std::numbers::pi / double(directions));
  const double g = double(unsigned(frame)) * 0.6180339887498949;
  jitter_shift = float(g - std::floor(g));
}

std::vector<float> step_fractions(const HorizonConfig& c, float jitter) {
  std::vector<float> f(c.steps + c.gather_steps);
  for (int k = 0; k < c.steps; ++k)
    f[k] = std::pow((float(k) + jitter) / float(c.steps), c.step_power);
  for (int k = 0; k < c.gather_steps; ++k)
    f[c.steps + k] = (float(k) + jitter) / float(c.gather_steps);
  return f;
}

SliceTerms integrate_slice(float theta0, float theta1, float nx, float ny) {
  // Antiderivatives of f(θ)|sin θ| that vanish at θ = 0; for θ < 0 the sign flips with
  // |sin θ| = −sin θ.  ∫_0^θ sin²  = (θ − sin θ cos θ)/2,  ∫_0^θ sin cos = sin² θ / 2.
  auto terms = [nx, ny](float t) {
    const float s = std::sin(t), c = std::cos(t), a = sgn(t);
    const float sin2 = (t - s * c) * 0.5f, sincos = s * s * 0.5f;
    SliceTerms r;
    r.ao = a * (nx * sin2 + ny * sincos);  // eq. 11 with the |sin θ| Jacobian
    r.vis = a * (1.f - c);
    r.bx = a * sin2;    // eq. 5, likewise
    r.by = a * sincos;  // eq. 6
    return r;
  };
  const SliceTerms g1 = terms(theta1), g0 = terms(theta0);
  return {g1.ao - g0.ao, g1.vis - g0.vis, g1.bx - g0.bx, g1.by - g0.by};
}

namespace {

// ∫_0^θ f(ω'(θ))|sin θ| dθ of the four slice integrands at one angle (see integrate_slice).
struct Antiderivative {
  float ao, vis, bx, by;
};
inline Antiderivative antiderivative(float t, float s, float c, float nx, float ny) {
  const float a = sgn(t), sin2 = (t - s * c) * 0.5f, sincos = s * s * 0.5f;
  return {a * (nx * sin2 + ny * sincos), a * (1.f - c), a * sin2, a * sincos};
}

// HBIL §3.4 rejection filter: a neighbour whose normal n' faces away from the receiver
// (−n'·ω_i < 0, ω_i from receiver to neighbour) occludes but sends no light. The fade
// smoothstep(−0.1, 0.1, −n'·ω_i) accepts neighbours seen at up to ~84 degrees from their
// normal fully and rejects those facing away by more than ~96 degrees.
inline float facing_weight(const Vec3& n_s, const Vec3& w_i) {
  const float x = std::clamp((-dot(n_s, w_i) + 0.1f) / 0.2f, 0.f, 1.f);
  return x * x * (3.f - 2.f * x);
}

}  // namespace

PixelSums march_pixel(const SampleView& view, int i, int j, const Vec3& P, const Vec3& n,
                      const float* phi, int n_slices, const float* fraction,
                      const HorizonConfig& c) {
  PixelSums acc;
  const Vec3 wo = normalize_or_zero(-P);  // ω_o: towards the camera at the view-space origin
  const Vec3 ray_P = P / P.z;             // P's ray, scaled to z = 1
  // Screen-space search radius in texels: the world radius at this depth (HBAO, XeGTAO).
  const float focal = 0.5f * (c.fx + c.fy);
  // Never beyond the image: a larger radius would only step off screen.
  const float diagonal = std::hypot(float(view.width), float(view.height));
  const float r_tex = std::min(c.radius * focal / (P.z * float(view.stride)), diagonal);
  const float r2 = c.radius * c.radius;
  const bool gather = view.radiance != nullptr;
  // The gather may reach beyond the AO radius: gather_steps more samples per side between
  // the two radii, which only the gather sees (AO is the same with or without them).
  const bool far = gather && c.gather_steps > 0;
  const float rg_tex =
      far ? std::min(c.gather_radius * focal / (P.z * float(view.stride)), diagonal) : r_tex;
  const float rg2 = far ? c.gather_radius * c.gather_radius : r2;
  const int n_steps = c.steps + (far ? c.gather_steps : 0);
  constexpr int kSectors = 32;
  constexpr float kSectorWidth = kPi / kSectors;
  // Orthonormal basis of the plane orthogonal to ω_o; slice s has D = cos φ e1 + sin φ e2.
  const Vec3 e1 = normalize_or_zero(Vec3{1, 0, 0} - wo * wo.x);
  const Vec3 e2 = cross(wo, e1);
  for (int s = 0; s < n_slices; ++s) {
    const Vec3 D = e1 * std::cos(phi[s]) + e2 * std::sin(phi[s]);
    // The screen line of the slice: the image of P + εD, d(u, v)/dε ∝ (fx (D.x − r.x D.z),
    // fy (D.y − r.y D.z)) with r = P/P.z. Marching along it stays in the slice plane.
    const float gx = c.fx * (D.x - ray_P.x * D.z), gy = c.fy * (D.y - ray_P.y * D.z);
    const float gl = std::sqrt(gx * gx + gy * gy);
    if (!(gl > 0.f)) continue;
    const float dx = gx / gl, dy = gy / gl;       // unit screen direction, pixels
    const Vec3 dv{dx / c.fx, dy / c.fy, 0.f};     // change of the z = 1 ray per pixel along it
    const float nx = dot(n, D), ny = dot(n, wo);  // eq. 2: the normal projected on the slice
    const float gamma = std::atan2(nx, ny);       // angle of n' from ω_o
    auto G = [&](float t) { return antiderivative(t, std::sin(t), std::cos(t), nx, ny); };

    // Horizon method: the current horizons, starting at the tangent plane (§2.1); those of
    // the gather (g) see the samples up to the gather radius.
    float theta1 = std::min(gamma + 0.5f * kPi, kPi), theta0 = std::max(gamma - 0.5f * kPi, -kPi);
    float theta1_g = theta1, theta0_g = theta0;
    // Bitmask method: 32 sectors over [γ − π/2, γ + π/2]; sector k's cosine-weighted
    // integral is W[k] = G(b_k) − G(a_k), so AO keeps the definition of eq. 9.
    std::uint32_t occluded = 0, occluded_g = 0;
    Antiderivative bound[kSectors + 1];
    const float sector0 = gamma - 0.5f * kPi;
    if (c.bitmask) {
      // Boundaries by rotation: (sin, cos) of sector0 + kΔ without 33 sin/cos pairs.
      const float cd = std::cos(kSectorWidth), sd = std::sin(kSectorWidth);
      float sb = std::sin(sector0), cb = std::cos(sector0);
      for (int k = 0; k <= kSectors; ++k) {
        bound[k] = antiderivative(sector0 + k * kSectorWidth, sb, cb, nx, ny);
        const float sn = sb * cd + cb * sd;
        cb = cb * cd - sb * sd;
        sb = sn;
      }
    }
    Vec3 irradiance;

    for (int side = 0; side < 2; ++side) {
      const float sx = side == 0 ? dx : -dx, sy = side == 0 ? dy : -dy;
      const float sign = side == 0 ? 1.f : -1.f;  // θ > 0 on the +D side
      // Offset of step k along the line, texels.
      auto o_at = [&](int q) {
        return q < c.steps ? 1.f + (r_tex - 1.f) * fraction[q]
                           : std::max(r_tex, 1.f) + (rg_tex - r_tex) * fraction[q];
      };
      for (int k = 0; k < n_steps; ++k) {
        const bool near = k < c.steps;
        if (near && r_tex < 1.f) continue;  // the AO radius is under a texel
        const float o = o_at(k);
        const int oi = int(std::floor(sx * o + 0.5f)), oj = int(std::floor(sy * o + 0.5f));
        if (oi == 0 && oj == 0) continue;
        const int si = i + oi, sj = j + oj;
        if (si < 0 || sj < 0 || si >= view.width || sj >= view.height) break;  // screen edge
        const std::ptrdiff_t k_s = view.index(si, sj);
        Vec3 S = view.position[k_s];
        // Move S along its tangent plane onto the ray through the exact point of the line
        // (see horizon.h): that ray lies in the slice plane.
        const Vec3 ray = ray_P + dv * (sign * o) * float(view.stride);
        const Vec3& n_s = view.normal[k_s];
        const float denom = dot(ray, n_s);
        if (std::fabs(denom) > kGrazing * length(ray)) S = ray * (dot(S, n_s) / denom);
        const Vec3 d3 = S - P;  // background has z = 3e38, n = 0: |d3| > radius
        const float dist2 = dot(d3, d3);
        if (!(dist2 < rg2) || dist2 <= 0.f) continue;
        const bool in_ao = near && dist2 < r2;
        const float dist = std::sqrt(dist2);
        const float theta_f = sign * std::acos(std::clamp(dot(d3, wo) / dist, -1.f, 1.f));
        // Light the sample sends towards P (eq. 18: L_d(x') over the band it covers).
        auto radiance = [&] { return view.radiance[k_s] * facing_weight(n_s, d3 / dist); };
        if (!c.bitmask) {
          // A rise of the horizon occludes, and is lit by, the band it sweeps (eq. 18).
          auto rise = [&](float& t0, float& t1, float& lo, float& hi) {
            if (side == 0) {
              if (!(theta_f < t1)) return false;
              lo = theta_f, hi = t1, t1 = theta_f;
            } else {
              if (!(theta_f > t0)) return false;
              lo = t0, hi = theta_f, t0 = theta_f;
            }
            return true;
          };
          float lo, hi;
          if (in_ao) rise(theta0, theta1, lo, hi);
          if (gather && rise(theta0_g, theta1_g, lo, hi))
            irradiance += radiance() * (G(hi).ao - G(lo).ao);
        } else {
          // Therrien et al. 2023, Algorithm 1: the sample is an occluder of thickness t
          // along its view ray; it covers [θf, θb] and lights the sectors it newly covers.
          // Thickness: measured (back faces) where known, else the constant heuristic.
          const bool measured = view.thickness && view.thickness[k_s] >= 0.f;
          const float t = measured ? view.thickness[k_s] : c.thickness + c.thickness_growth * S.z;
          auto angle = [&](const Vec3& X) {
            const Vec3 d = X - P;
            return sign * fast_acos(std::clamp(dot(d, wo) / length(d), -1.f, 1.f));
          };
          const float theta_b = angle(S + S * (t / length(S)));
          float th_lo = std::min(theta_f, theta_b), th_hi = std::max(theta_f, theta_b);
          if (measured) {
            // A measured thickness is the object's own, so the sample must also stand for the
            // surface between it and its neighbours, which a point misses (light would leak
            // between samples on a wall): it covers its tangent plane between the rays
            // through the midpoints to its neighbours on the line, extruded by t along them.
            // (The constant thickness is a heuristic tuned with point samples; see horizon.h.)
            // The first sample reaches back only half way to P: nearer, the direction from P
            // to a point of another sample's plane is dominated by sub-pixel error (Blender's
            // depth is one jittered sample, P is placed at the pixel centre), so within about
            // one texel of a crease the surface between P and its first sample is missed.
            const float o_prev = k == 0 ? 0.f : std::min(o_at(k - 1), o);
            const float lo_o = 0.5f * (o + o_prev);
            // Neighbours within the same group only: the last sample of a group reaches as
            // far beyond itself as its predecessor is before it, never towards the
            // gather-only samples, so ao is the same with or without them.
            const bool last = k + 1 == (near ? c.steps : n_steps);
            const float hi_o =
                last ? o + 0.5f * (o - o_prev) : 0.5f * (o + std::max(o_at(k + 1), o));
            const float plane = dot(S, n_s);
            for (float oo : {lo_o, hi_o}) {
              const Vec3 r = ray_P + dv * (sign * oo) * float(view.stride);
              const float den = dot(r, n_s);
              if (!(std::fabs(den) > kGrazing * length(r))) continue;
              const Vec3 X = r * (plane / den);
              if (!(X.z > 0.f)) continue;
              const float a = angle(X), b = angle(X + X * (t / length(X)));
              th_lo = std::min(th_lo, std::min(a, b));
              th_hi = std::max(th_hi, std::max(a, b));
            }
          }
          const float lo = (th_lo - sector0) / kSectorWidth;
          const float hi = (th_hi - sector0) / kSectorWidth;
          // "Round" criterion: a sector counts when at least half covered.
          const int a = std::clamp(int(std::floor(lo + 0.5f)), 0, kSectors);
          const int b = std::clamp(int(std::floor(hi + 0.5f)), 0, kSectors);
          if (b <= a) continue;
          const std::uint32_t mask = (b - a == 32 ? ~0u : ((1u << (b - a)) - 1u)) << a;
          if (in_ao) occluded |= mask;
          if (!gather) continue;
          std::uint32_t fresh = mask & ~occluded_g;
          occluded_g |= mask;
          if (fresh) {
            float w = 0.f;
            for (; fresh; fresh &= fresh - 1) {
              const int q = std::countr_zero(fresh);
              w += bound[q + 1].ao - bound[q].ao;
            }
            irradiance += radiance() * w;
          }
        }
      }
    }
    if (!c.bitmask) {
      theta1 = std::max(theta1, theta0);
      const SliceTerms t = integrate_slice(theta0, theta1, nx, ny);
      acc.ao += t.ao;
      acc.vis += t.vis;
      acc.bent += D * t.bx + wo * t.by;
    } else {
      for (int k = 0; k < kSectors; ++k) {
        if (occluded >> k & 1u) continue;
        acc.ao += bound[k + 1].ao - bound[k].ao;
        acc.vis += bound[k + 1].vis - bound[k].vis;
        acc.bent += D * (bound[k + 1].bx - bound[k].bx) + wo * (bound[k + 1].by - bound[k].by);
      }
    }
    acc.irradiance += irradiance;
  }
  return acc;
}

}  // namespace hbil
