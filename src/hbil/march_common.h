// march_common.h: what the horizon and bitmask marches share (internal to src/hbil): the
// per-pixel frame of the slices, one slice's screen line, the slice antiderivatives and the
// HBIL §3.4 rejection filter. The vectorised bitmask march (march_bitmask_simd.cpp) repeats
// these formulas lane by lane in the same order of operations, so that it reproduces the
// scalar reference to the bit (tests/march_test.cpp).
#pragma once

#include <algorithm>
#include <climits>
#include <cmath>
#include <cstdint>
#include <numbers>

#include "hbil/gbuffer.h"
#include "hbil/horizon.h"

namespace hbil::march {

constexpr float kPi = std::numbers::pi_v<float>;
inline float sgn(float t) {
  return t < 0.f ? -1.f : 1.f;
}
// Below this |cos| between the sample's normal and the corrected ray the tangent-plane
// correction is unstable (silhouettes, poles seen side-on) and the sample is used as is.
// Chosen by hand on the samples' poles (0.05-0.2 change AO by < 0.001 RMS); not tuned.
constexpr float kGrazing = 0.1f;
constexpr float kGrazing2 = kGrazing * kGrazing;  // the same test on squares
// acos to 7e-5 rad (Abramowitz & Stegun 4.4.45), well under the bitmask's sector width of
// π/32 = 0.098 rad: every angle of the bitmask method is only quantised to sectors. The
// horizon march's angles move by as little (no accuracy figure of bench/tables.sh changes),
// and std::acos was a third of its time.
inline float fast_acos(float x) {
  const float a = std::fabs(x);
  const float r =
      std::sqrt(1.f - a) * (1.5707288f + a * (-0.2121144f + a * (0.0742610f - 0.0187293f * a)));
  return x < 0.f ? kPi - r : r;
}

// atan2(y, x) to 4e-7 rad (floats near π are 2.4e-7 apart; libm's atan2f is within one of
// them), in a form that vectorises: march_simd-inl.h repeats it lane by lane. Every angle of
// the bitmask method is quantised to sectors of 0.098 rad. atan(a) for a = min / max of
// |x|, |y| in [0, 1] is a P(a²), P of degree 7 fitted to the relative error (1.1e-7 rad at
// most), then unfolded to the octant. atan2(0, 0) is 0.
// P's coefficients, highest degree first (Horner's order).
constexpr float kAtanPoly[8] = {-0.0040553999f, 0.021865912f, -0.055916518f, 0.096425004f,
                                -0.13908748f,   0.19946590f,  -0.33329862f,  0.99999934f};
inline float fast_atan2(float y, float x) {
  const float ax = std::fabs(x), ay = std::fabs(y);
  const float hi = std::max(ax, ay), lo = std::min(ax, ay);
  const float a = hi > 0.f ? lo / hi : 0.f, s = a * a;
  float p = kAtanPoly[0];
  for (int k = 1; k < 8; ++k) p = p * s + kAtanPoly[k];
  float r = a * p;
  if (ay > ax) r = 0.5f * kPi - r;
  if (x < 0.f) r = kPi - r;
  return y < 0.f ? -r : r;
}

// The bitmask's sectors over the slice's visible half circle.
constexpr int kSectors = 32;
constexpr float kSectorWidth = kPi / kSectors;
constexpr float kInvSectorWidth = 1.f / kSectorWidth;  // a multiply where a divide would cost

// ∫_0^θ f(ω'(θ))|sin θ| dθ of the four slice integrands at one angle (see integrate_slice),
// with s, c = sin θ, cos θ.
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
// normal fully and rejects those facing away by more than ~96 degrees. Takes n'·ω_i, which
// the marches form as n'·(X − P) / |X − P| (one divide, not three).
inline float facing_weight(float n_dot_wi) {
  const float x = std::clamp((0.1f - n_dot_wi) * 5.f, 0.f, 1.f);
  return x * x * (3.f - 2.f * x);
}

// What one pixel's slices share: ω_o, its ray, its search radii in texels, and the basis
// of the plane orthogonal to ω_o in which the slice directions turn.
struct PixelFrame {
  Vec3 wo;           // towards the camera at the view-space origin
  Vec3 ray_P;        // P's ray, scaled to z = 1 (exactly 1)
  float r_tex = 0;   // AO radius, texels
  float rg_tex = 0;  // gather radius, texels (= r_tex without gather-only samples)
  Vec3 e1, e2;       // slice s has D = cos φ e1 + sin φ e2
};
inline PixelFrame pixel_frame(const SampleView& view, const Vec3& P, const HorizonConfig& c,
                              bool far) {
  PixelFrame f;
  f.wo = normalize_or_zero(-P);
  f.ray_P = Vec3{P.x / P.z, P.y / P.z, 1.f};  // z = 1 exactly (the marches' rays keep it)
  // Screen-space search radius in texels: the world radius at this depth (HBAO, XeGTAO),
  // never beyond the image (a larger radius would only step off screen).
  const float focal = 0.5f * (c.fx + c.fy);
  const float diagonal = std::hypot(float(view.width), float(view.height));
  f.r_tex = std::min(c.radius * focal / (P.z * float(view.stride)), diagonal);
  f.rg_tex =
      far ? std::min(c.gather_radius * focal / (P.z * float(view.stride)), diagonal) : f.r_tex;
  f.e1 = normalize_or_zero(Vec3{1, 0, 0} - f.wo * f.wo.x);
  f.e2 = cross(f.wo, f.e1);
  return f;
}

// One slice of one pixel: its direction D, the unit screen direction (dx, dy) of its line,
// the change dv of the z = 1 ray per pixel along it, and the normal projected on the slice.
struct SliceLine {
  Vec3 D;
  float dx = 0, dy = 0;
  Vec3 dv;
  float nx = 0, ny = 0;  // eq. 2: n' = (n·D, n·ω_o)
};
// False when the slice has no screen line (D along the pixel's ray).
inline bool slice_line(const PixelFrame& f, const Vec3& n, float cos_phi, float sin_phi,
                       const HorizonConfig& c, SliceLine& s) {
  s.D = f.e1 * cos_phi + f.e2 * sin_phi;
  // The image of P + εD: d(u, v)/dε ∝ (fx (D.x − r.x D.z), fy (D.y − r.y D.z)) with r = P/P.z.
  // Marching along it stays in the slice plane.
  const float gx = c.fx * (s.D.x - f.ray_P.x * s.D.z), gy = c.fy * (s.D.y - f.ray_P.y * s.D.z);
  const float gl = std::sqrt(gx * gx + gy * gy);
  if (!(gl > 0.f)) return false;
  s.dx = gx / gl;
  s.dy = gy / gl;
  s.dv = Vec3{s.dx / c.fx, s.dy / c.fy, 0.f};
  s.nx = dot(n, s.D);
  s.ny = dot(n, f.wo);
  return true;
}

// Offset along the line of step q, texels: the AO samples spread over [1, r_tex], the
// gather-only ones over [r_tex, rg_tex].
inline float step_offset(int q, int steps, float r_tex, float rg_tex, const float* fraction) {
  return q < steps ? 1.f + (r_tex - 1.f) * fraction[q]
                   : std::max(r_tex, 1.f) + (rg_tex - r_tex) * fraction[q];
}

// What one pixel's march needs before its slices: whether it gathers light and reaches
// beyond the AO radius with gather-only samples, the squared radii and the samples per side.
struct MarchSetup {
  bool gather = false;  // a radiance source is given
  bool far = false;     // gather_steps more samples per side between the two radii, which
                        // only the gather sees (AO is the same with or without them)
  PixelFrame f;
  float r2 = 0, rg2 = 0;
  int n_steps = 0;
};
inline MarchSetup march_setup(const SampleView& view, const Vec3& P, const HorizonConfig& c) {
  MarchSetup m;
  m.gather = view.radiance != nullptr;
  m.far = m.gather && c.gather_steps > 0;
  m.f = pixel_frame(view, P, c, m.far);
  m.r2 = c.radius * c.radius;
  m.rg2 = m.far ? c.gather_radius * c.gather_radius : m.r2;
  m.n_steps = c.steps + (m.far ? c.gather_steps : 0);
  return m;
}

// int(std::floor(v)) for |v| < 2²², else ±2²² (a NaN gives 2²²), without the undefined
// conversion of a float out of int's range: a step's offset in texels is under the view's
// diagonal where the pixel lies in front of the camera, and anything clamped falls off a
// view under 2²¹ texels a side (march_row_scalar_if_too_large) as it would unclamped.
// FloorToInt (march_simd-inl.h) is the same, lane by lane.
constexpr float kOffsetLimit = 4194304.f;  // 2²²
inline int floor_to_int(float v) {
  // x86's min(v, limit) and max(·, −limit): a NaN v gives the limit.
  const float below = v < kOffsetLimit ? v : kOffsetLimit;
  return int(std::floor(below > -kOffsetLimit ? below : -kOffsetLimit));
}

// Step k of one side of a slice (sx, sy: its screen direction; sign: +1 on the +D side).
enum class StepResult { use, skip, edge };
struct Step {
  float o = 0;             // offset along the line, texels
  std::ptrdiff_t k_s = 0;  // the sample's texel
  Vec3 S, d3;              // the sample, moved onto the slice plane, and S − P
  float dist2 = 0;         // |d3|²
};
inline StepResult take_step(const SampleView& view, int i, int j, int k, float sx, float sy,
                            float sign, const Vec3& P, const SliceLine& L, const MarchSetup& m,
                            const HorizonConfig& c, const float* fraction, Step& st) {
  if (k < c.steps && m.f.r_tex < 1.f) return StepResult::skip;  // AO radius under a texel
  st.o = step_offset(k, c.steps, m.f.r_tex, m.f.rg_tex, fraction);
  const int oi = floor_to_int(sx * st.o + 0.5f), oj = floor_to_int(sy * st.o + 0.5f);
  if (oi == 0 && oj == 0) return StepResult::skip;
  const int si = i + oi, sj = j + oj;
  if (si < 0 || sj < 0 || si >= view.width || sj >= view.height) return StepResult::edge;
  st.k_s = view.index(si, sj);
  st.S = view.position[st.k_s];
  // Move S along its tangent plane onto the ray through the exact point of the line (see
  // horizon.h): that ray lies in the slice plane.
  const Vec3 ray = m.f.ray_P + L.dv * (sign * st.o) * float(view.stride);
  const Vec3& n_s = view.normal[st.k_s];
  const float denom = dot(ray, n_s);
  if (denom * denom > kGrazing2 * dot(ray, ray)) st.S = ray * (dot(st.S, n_s) / denom);
  st.d3 = st.S - P;  // background has z = 3e38, n = 0: |d3| > radius
  st.dist2 = dot(st.d3, st.d3);
  if (!(st.dist2 < m.rg2) || st.dist2 <= 0.f) return StepResult::skip;
  return StepResult::use;
}

// The SIMD row marches index the view's floats with 32-bit lane integers, and round a step's
// offset in texels (under the view's diagonal) through a float with 23 bits to spare
// (FloorToInt): a view too large for them (more than about 700 million texels, or 2²¹
// texels a side) is marched pixel by pixel by the scalar reference, march_one(i, P, n)
// giving the sums of texel (i, j).
template <class MarchOne>
bool march_row_scalar_if_too_large(const SampleView& view, int i0, int j, int count, PixelSums* out,
                                   MarchOne march_one) {
  const std::int64_t last =
      std::int64_t(view.height - 1) * view.row + std::int64_t(view.width - 1) * view.col;
  constexpr int kSide = 1 << 21;
  if (3 * last + 2 <= std::int64_t(INT32_MAX) && view.width < kSide && view.height < kSide)
    return false;
  for (int k = 0; k < count; ++k) {
    const std::ptrdiff_t at = view.index(i0 + k, j);
    if (!(view.position[at].z < ViewGBuffer::kBackground)) continue;
    out[k] = march_one(i0 + k, view.position[at], view.normal[at]);
  }
  return true;
}

}  // namespace hbil::march
