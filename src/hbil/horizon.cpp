// horizon.cpp: see horizon.h for the paper sections and departures.
#include "hbil/horizon.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <numbers>

#include "hbil/march_common.h"

namespace hbil {

HorizonConfig make_horizon_config(const Params& p, const Camera& cam) {
  HorizonConfig c;
  c.radius = float(p.radius);
  c.steps = p.steps;
  c.step_power = float(p.step_power);
  c.fx = float(cam.fx);
  c.fy = float(cam.fy);
  c.bitmask = p.method == "bitmask";
  c.vectorised = p.vectorised;
  c.thickness = float(p.thickness);
  // Unresolved "auto" (a library call outside a sequence job): the samples' thickness.
  c.gather_thickness = float(p.gather_thickness_auto ? p.thickness : p.gather_thickness);
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

std::vector<std::uint64_t> texel_surfaces(const Vec3* position, const Vec3* normal, size_t count) {
  // The marches' dot(S, n_s) to the bit: this file is compiled without fused multiply-adds.
  auto word = [](float lo, float hi) {
    return std::uint64_t(std::bit_cast<std::uint32_t>(lo)) |
           std::uint64_t(std::bit_cast<std::uint32_t>(hi)) << 32;
  };
  std::vector<std::uint64_t> surface(2 * count);
  for (size_t k = 0; k < count; ++k) {
    surface[2 * k] = word(normal[k].x, normal[k].y);
    surface[2 * k + 1] = word(normal[k].z, dot(position[k], normal[k]));
  }
  return surface;
}

SliceTerms integrate_slice(float theta0, float theta1, float nx, float ny) {
  // Antiderivatives of f(θ)|sin θ| that vanish at θ = 0 (march::antiderivative): eq. 11, 5
  // and 6 with the |sin θ| Jacobian.
  const auto g1 = march::antiderivative(theta1, std::sin(theta1), std::cos(theta1), nx, ny);
  const auto g0 = march::antiderivative(theta0, std::sin(theta0), std::cos(theta0), nx, ny);
  return {g1.ao - g0.ao, g1.vis - g0.vis, g1.bx - g0.bx, g1.by - g0.by};
}

}  // namespace hbil
