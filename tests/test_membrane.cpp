// The flexible membranes (docs/physics.md §6.3, protocol/membrane.hpp): which grains form the 2D
// chains and the 3D membrane's nodes, and their loads against numbers worked by hand.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <numbers>
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

TEST(Membrane2D, ASmallGrainUnderThePlatenIsNotAChainGrain) {
  // Columns of R = 0.5 mm disks at x = 0 and 10 mm, rows at y = 0.5 ... 5.5 mm, platens at 0 and
  // 6.3 mm, and a disk of 0.1 mm touching the top platen mid-sample at (5, 6.2) mm. The mean
  // diameter, 12/13 mm, cuts 6 whole cells and 0.72 of a seventh; the seventh would hold the
  // small disk alone, which would then be both chains' top grain, a spike into the sample. The
  // last cell takes the remainder: every surface lies on the sides, the width is 11 mm, and the
  // small disk carries no membrane load.
  ParticleStore ps(Dimension::Two, 1e-3);
  const double mm = 1e-3;
  std::uint64_t tag = 1;
  for (int row = 0; row < 6; ++row)
    for (const double x : {0.0, 10.0})
      ps.add({.tag = tag++,
              .position = {x * mm, (row + 0.5) * mm, 0},
              .radius = 0.5 * mm,
              .density = 2650});
  ps.add({.tag = tag, .position = {5 * mm, 6.2 * mm, 0}, .radius = 0.1 * mm, .density = 2650});
  Simulation sim = planar_sim(std::move(ps));
  Membrane2D m;
  m.apply(sim, 1e6, 0.0, 6.3 * mm);
  EXPECT_EQ(m.chains()[0].size(), 6u);
  EXPECT_EQ(m.chains()[1].size(), 6u);
  EXPECT_NEAR(m.width(sim.particles()), 11 * mm, 1e-12);
  const Vec3 small = sim.external_force()[12];
  EXPECT_EQ(small.x, 0.0);
  EXPECT_EQ(small.y, 0.0);
}

namespace {

// Columns of equal grains (radius r) around the z axis at radius rho, one grain per cell: with
// rho + r = 12 r / pi the membrane cuts 12 columns (round(2 pi (rho + r) / 2r)), and layers 2r
// apart between platens 6r apart make 3 rows. `rho_of_row` bulges a row; `skip` leaves a cell
// empty (column, row); `inner` adds a grain 1.5 r inside column 0 of the middle row.
struct Column {
  double r = 1e-3;
  double rho = 1e-3 * (12.0 / std::numbers::pi - 1.0);
  double theta(int k) const { return -std::numbers::pi + (k + 0.5) * 2.0 * std::numbers::pi / 12; }
  Simulation build(const double (&rho_of_row)[3], std::pair<int, int> skip = {-1, -1},
                   bool inner = false) const {
    ParticleStore ps(Dimension::Three, 1.0);
    std::uint64_t tag = 1;
    for (int row = 0; row < 3; ++row)
      for (int k = 0; k < 12; ++k) {
        if (k == skip.first && row == skip.second) continue;
        const double p = rho_of_row[row];
        ps.add({.tag = tag++,
                .position = {p * std::cos(theta(k)), p * std::sin(theta(k)), (2 * row + 1) * r},
                .radius = r,
                .density = 2650});
      }
    if (inner)
      ps.add({.tag = tag++,
              .position = {(rho - 1.5 * r) * std::cos(theta(0)),
                           (rho - 1.5 * r) * std::sin(theta(0)), 3 * r},
              .radius = r,
              .density = 2650});
    EngineConfig cfg;
    cfg.time_step = 1e-8;
    return Simulation(std::move(ps), cfg, make_contact_model<LinearContact>({}, {}));
  }
};

}  // namespace

// Hand numbers: a face between neighbouring columns, h tall, has the area h L along the radius
// through its middle, L = 2 rho sin(pi/12) the chord; its load sigma_3 h L goes a quarter to each
// corner. A grain of the middle row is a corner of four faces 2r tall; one of the end rows of two
// faces r tall whose ring corners are its own (a half each) and two 2r tall (a quarter each).
// Either way the two sides' loads, pi/12 either side of the grain's radius, add up to sigma_3 h L
// 2 cos(pi/12) with h = r: sigma_3 rho r inward along its radius.
TEST(MembraneCylinder, StraightColumnsCarrySigma3RhoRInwardEach) {
  const Column c;
  const double sigma3 = 5e6, rows[3] = {c.rho, c.rho, c.rho};
  Simulation sim = c.build(rows);
  MembraneCylinder m;
  m.apply(sim, sigma3, {0, 0, 0}, 0.0, 6 * c.r);
  EXPECT_EQ(m.columns(), 12u);
  EXPECT_EQ(m.rows(), 3u);
  EXPECT_EQ(m.grains().size(), 36u);
  const auto& f = sim.external_force();
  const ParticleStore& p = sim.particles();
  const double expected = sigma3 * c.rho * c.r;
  for (std::size_t i = 0; i < p.size(); ++i) {
    const Vec3 x = p.pos_rad[i].x;
    const Vec3 inward{-x.x / c.rho, -x.y / c.rho, 0.0};
    EXPECT_NEAR(dot(f[i], inward), expected, 1e-9 * expected) << i;
    EXPECT_NEAR(norm(f[i] - inward * dot(f[i], inward)), 0.0, 1e-9 * expected) << i;
  }
  EXPECT_NEAR(m.stress(), sigma3, 1e-12 * sigma3);
  EXPECT_NEAR(m.diameter(p), 2.0 * (c.rho + c.r), 1e-15);
}

// A bulged middle row: the loads are no longer radial at the end rows (the faces lean), but the
// faces tile a surface whose ends are equal polygons, so the loads sum to zero in every
// direction, and the radial parts to sigma_3 times the faces' radial area (stress() = sigma_3).
// A grain inside the outermost one of its cell carries nothing.
TEST(MembraneCylinder, BulgedSidesAreLoadedInBalanceAndInnerGrainsAreNot) {
  const Column c;
  const double sigma3 = 5e6, rows[3] = {c.rho, c.rho + 0.5 * c.r, c.rho};
  Simulation sim = c.build(rows, {-1, -1}, true);
  MembraneCylinder m;
  m.apply(sim, sigma3, {0, 0, 0}, 0.0, 6 * c.r);
  const auto& f = sim.external_force();
  Vec3 total{};
  for (const Vec3& x : f) total += x;
  const double scale = sigma3 * c.rho * c.r;
  EXPECT_NEAR(norm(total), 0.0, 1e-9 * scale);
  EXPECT_EQ(norm(f.back()), 0.0) << "the inner grain";
  EXPECT_EQ(m.grains().size(), 36u);
  EXPECT_NEAR(m.stress(), sigma3, 1e-12 * sigma3);
  // The end rows' grains are pulled toward the bulge (their faces lean outward going up or
  // down), the middle row's pushed straight in.
  const ParticleStore& p = sim.particles();
  for (std::size_t i = 0; i < 36; ++i) {
    const double z = p.pos_rad[i].x.z;
    if (std::abs(z - c.r) < 1e-12) {
      EXPECT_GT(f[i].z, 0.0) << i;
    } else if (std::abs(z - 5 * c.r) < 1e-12) {
      EXPECT_LT(f[i].z, 0.0) << i;
    } else {
      EXPECT_NEAR(f[i].z, 0.0, 1e-9 * scale) << i;
    }
  }
  // The diameter lies between the end rows' reach and the bulge's.
  EXPECT_GT(m.diameter(p), 2.0 * (c.rho + c.r));
  EXPECT_LT(m.diameter(p), 2.0 * (c.rho + 1.5 * c.r));
}

// A cell without a grain takes the grain of the next cell around the axis, which then stands at
// two nodes and carries both shares; the membrane still holds sigma_3 over its faces.
TEST(MembraneCylinder, AnEmptyCellTakesTheNextCellsGrain) {
  const Column c;
  const double sigma3 = 5e6, rows[3] = {c.rho, c.rho, c.rho};
  Simulation sim = c.build(rows, {3, 1});
  MembraneCylinder m;
  m.apply(sim, sigma3, {0, 0, 0}, 0.0, 6 * c.r);
  EXPECT_EQ(m.grains().size(), 35u);
  EXPECT_NEAR(m.stress(), sigma3, 1e-12 * sigma3);
  // Column 4's middle grain (index 12 + 4 - 1: the skipped cell came before it) takes column
  // 3's faces too, so it carries more than a grain of its own.
  const auto& f = sim.external_force();
  const double alone = sigma3 * c.rho * c.r;
  EXPECT_GT(norm(f[12 + 3]), 1.5 * alone);
}
