// Elastic moduli of a bonded hexagonal disk lattice against the closed form of docs/physics.md
// §7.5: E_2D = 2 sqrt(3) K_n (K_n + K_s) / (t (3 K_n + K_s)), nu_2D = (K_n - K_s) / (3 K_n + K_s).
// The lattice is strained affinely (exact here: rotations stay zero under uniform strain) and the
// stress of an interior particle is taken from its bond forces (§6.5).
#include <gtest/gtest.h>

#include <cmath>

#include "breccia/engine/simulation.hpp"
#include "breccia/sample/lattice.hpp"

using namespace breccia;

namespace {

struct Moduli {
  double e2d, nu2d;
};

// Uniaxial strain eps_xx at rate `rate` (negative: extension), returns the plane Lame moduli
// turned into E_2D and nu_2D.
Moduli measure(double rate, double contact_modulus) {
  const double R = 0.5e-3, t = 2e-3;
  ParticleStore ps = hex_block(9, 9, R, 2650, t);
  const std::size_t centre = 4 * 9 + 4;
  const Vec3 xc = ps.pos_rad[centre].x;
  for (std::size_t i = 0; i < ps.size(); ++i) {
    ps.set_motion(i, Motion::Driven);
    ps.drive_vel[i] = {-rate * (ps.pos_rad[i].x.x - xc.x), 0, 0};
    ps.vel[i] = ps.drive_vel[i];
  }
  EngineConfig cfg;
  cfg.energy_interval = 0;
  LinearContact::Params lp;
  lp.modulus = contact_modulus;
  lp.friction = 10.0;  // the closed form is elastic: no Coulomb sliding of the contacts
  Simulation sim(std::move(ps), cfg, make_contact_model<LinearContact>(lp, lp));
  sim.bond_touching_pairs<ParallelBond>(1e-9);
  sim.initialise();
  sim.run(400);
  const double x0 = sim.particles().pos_rad[centre + 1].x.x - sim.particles().pos_rad[centre].x.x;
  sim.step();  // forces of this step belong to the configuration measured above
  const double eps = 1.0 - x0 / (2 * R);  // compression-positive strain
  // Stress of the centre particle: half of l (x) F over its pairs (bond and contact of a pair
  // share one summed force) divided by the cell area 2 sqrt(3) R^2 t.
  double sxx = 0, syy = 0;
  std::visit(
      [&](const auto& c) {
        for (std::size_t k = 0; k < c.pairs.size(); ++k) {
          const auto i = c.pairs.first[k], j = c.pairs.second[k];
          if (i != centre && j != centre) continue;
          const Vec3 l = sim.particles().pos_rad[j].x - sim.particles().pos_rad[i].x;
          const Vec3 f = sim.pair_force(c, k);  // on particle j (particle 2)
          sxx += 0.5 * l.x * f.x;
          syy += 0.5 * l.y * f.y;
        }
      },
      sim.contact_model());
  const double area = 2 * std::sqrt(3.0) * R * R * t;
  sxx /= area * eps;  // lambda + 2 mu
  syy /= area * eps;  // lambda
  const double lambda = syy, mu = 0.5 * (sxx - syy);
  return {4 * mu * (lambda + mu) / (lambda + 2 * mu), lambda / (lambda + 2 * mu)};
}

Moduli closed_form(double kn, double ks, double t) {
  return {2 * std::sqrt(3.0) * kn * (kn + ks) / (t * (3 * kn + ks)), (kn - ks) / (3 * kn + ks)};
}

}  // namespace

TEST(HexLattice2D, ParallelBondAloneMatchesClosedForm) {
  // Extension: contacts never engage, the bonds alone carry the load. K_n = E_bar t, K_s = K_n/2.5.
  const double t = 2e-3, kn = 10e9 * t;
  const Moduli m = measure(-0.5, 10e9);
  const Moduli ref = closed_form(kn, kn / 2.5, t);
  EXPECT_NEAR(ref.e2d / 10e9, 1.426, 1e-3);  // docs/physics.md's quoted value
  EXPECT_NEAR(ref.nu2d, 0.176, 1e-3);
  EXPECT_NEAR(m.e2d, ref.e2d, 0.01 * ref.e2d);
  EXPECT_NEAR(m.nu2d, ref.nu2d, 0.01 * ref.nu2d);
}

TEST(HexLattice2D, BondsAndContactsInParallelMatchClosedForm) {
  // Compression: every bonded pair overlaps, so the linear contact (k_n = E_c t for equal disks,
  // k_s = k_n / 2.5) adds its springs to the bond's.
  const double t = 2e-3;
  const double kn = 10e9 * t + 30e9 * t;
  const Moduli m = measure(0.5, 30e9);
  const Moduli ref = closed_form(kn, kn / 2.5, t);
  EXPECT_NEAR(m.e2d, ref.e2d, 0.01 * ref.e2d);
  EXPECT_NEAR(m.nu2d, ref.nu2d, 0.01 * ref.nu2d);
}
