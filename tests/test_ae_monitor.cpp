// The acoustic-emission monitor on a hand-built tensile source: a bonded chain of five grains
// along x pulled apart at its ends. When a bond breaks, the tension T that the source grains
// exerted on their outside neighbours is released, so the moment tensor is the opening dipole
// M = diag(M_xx, 0, 0) with M_xx > 0: Hudson (u, v) = (-2/3, 1/3), R ratio 42.9 (docs/analysis.md
// §4.2-§4.3). Statically the release is T on each outside contact at lever arm l (contact point
// minus crack midpoint), so M_xx = T sum(l); the dynamic maximum lies between that and twice it
// (an undamped release overshoots by at most 2x).
#include <gtest/gtest.h>

#include <cmath>

#include "breccia/analysis/moment_tensor.hpp"
#include "breccia/observe/ae_monitor.hpp"

using namespace breccia;

namespace {

Simulation pulled_chain(std::uint64_t seed, double damping) {
  const double R = 0.5e-3;
  ParticleStore ps(Dimension::Three, 1.0);
  for (int k = 0; k < 5; ++k)
    ps.add({.tag = static_cast<std::uint64_t>(k + 1),
            .position = {2 * R * k, 0, 0},
            .radius = R,
            .density = 2650});
  const double v = 0.02;
  ps.set_motion(0, Motion::Driven);
  ps.set_motion(4, Motion::Driven);
  ps.drive_vel[0] = ps.vel[0] = {-v, 0, 0};
  ps.drive_vel[4] = ps.vel[4] = {v, 0, 0};
  EngineConfig cfg;
  cfg.local_damping = damping;
  cfg.seed = seed;
  LinearContact::Params lp;
  Simulation sim(std::move(ps), cfg, make_contact_model<LinearContact>(lp, lp));
  ParallelBond::Params bp;
  bp.tensile_strength = 2e6;
  bp.tensile_strength_sd = 0.3e6;  // one bond is the weakest
  bp.cohesion = 1e9;
  sim.set_bond_params<ParallelBond>(bp);
  sim.bond_touching_pairs<ParallelBond>(1e-9);
  sim.initialise();
  return sim;
}

}  // namespace

TEST(AeMonitor, TensileChainBreakIsAnOpeningDipole) {
  for (std::uint64_t seed : {1u, 2u, 3u}) {
    Simulation sim = pulled_chain(seed, 0.7);
    AeSettings s;
    s.source_radius = 1.5e-3;  // the bond's grains only touch their chain neighbours
    AeMonitor ae(s);
    ae.configure(100.0);  // T_d = 4 r_s / v_S = 60 us: the chain relaxes well within it
    std::size_t steps = 0;
    while (sim.cracks().empty() && steps < 2000000) {
      sim.step();
      ++steps;
      ae.after_step(sim, 0.0, 0.0);
    }
    ASSERT_FALSE(sim.cracks().empty()) << "the chain must break";
    const CrackRecord c = sim.cracks().front();
    const double T = -c.Fn;  // tension at failure (Fn is compression-positive)
    ASSERT_GT(T, 0.0);
    for (int k = 0; k < 200000 && (ae.has_open_events() || ae.event_count() == 0); ++k) {
      sim.step();
      ae.after_step(sim, 0.0, 0.0);
    }
    ae.finish();
    const std::vector<AeEvent> events = ae.events();
    ASSERT_GE(events.size(), 1u);
    const AeEvent& e = events.front();
    // Lever arms of the outside contacts of the two source grains (the chain's neighbours that
    // exist and are not themselves source grains).
    const auto& p = sim.particles();
    const std::size_t i1 = p.index_of(c.id1), i2 = p.index_of(c.id2);
    double arms = 0.0;
    for (std::size_t q : {std::min(i1, i2) - 1, std::max(i1, i2) + 1})
      if (q < p.size())
        arms += std::abs(c.position.x -
                         (q < i1 ? p.pos_rad[q].x.x + 0.5e-3 : p.pos_rad[q].x.x - 0.5e-3));
    analysis::Tensor3 m{};
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) m[i][j] = e.moment[static_cast<std::size_t>(3 * i + j)];
    const analysis::SourceType st = analysis::source_type(m);
    EXPECT_GT(m[0][0], 0.0) << "opening: positive trace";
    EXPECT_NEAR(m[0][0], st.eigenvalues[0], 1e-12 * std::abs(m[0][0])) << "only M_xx";
    EXPECT_NEAR(st.u, -2.0 / 3.0, 1e-6) << seed;
    EXPECT_NEAR(st.v, 1.0 / 3.0, 1e-6) << seed;
    EXPECT_NEAR(st.r_ratio, 42.857, 1e-3) << seed;
    EXPECT_GE(m[0][0], 0.8 * T * arms) << seed;
    EXPECT_LE(m[0][0], 2.0 * T * arms) << seed;
    EXPECT_GT(e.ke_gain, 0.0) << "the release sets grains in motion";
  }
}
