// The RICEBAL 2D bond (docs/physics.md §4.4) against numbers worked by hand: its stiffnesses on the
// circle of the smaller grain (planar spheres) or the slab (disks), its tensile check with the
// moment, its shear envelope in tension and in compression, and the engine judging it on the
// interface totals with a Hertz-Mindlin contact pressing the grains together.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <string>

#include "breccia/engine/simulation.hpp"
#include "breccia/spec/experiment.hpp"
#include "pair_harness.hpp"

using namespace breccia;
using namespace breccia::test;

namespace {

constexpr double kR = 0.5e-3, kPi = std::numbers::pi;

// Two planar spheres of radius R touching along x, bonded where they stand.
PairStepper<RicebalBond> touching_pair(double gap = 0.0) {
  PairStepper<RicebalBond> s;
  s.a.x = {0, 0, 0};
  s.b.x = {2 * kR + gap, 0, 0};
  s.install();
  return s;
}

}  // namespace

TEST(RicebalBond, StiffnessesFollowTheSmallerGrainsCircle) {
  // E_b = 10 GPa, nu_b = 0.2: G_b = 10 / 2.4 GPa; A_b = pi R^2, I_b = pi R^4 / 4, d0 = 2R.
  auto s = touching_pair();
  const double A = kPi * kR * kR, I = 0.25 * kPi * std::pow(kR, 4), d0 = 2 * kR;
  EXPECT_NEAR(s.state.kn, 10e9 * A / d0, 1e-9 * s.state.kn);
  EXPECT_NEAR(s.state.ks, 10e9 / 2.4 * A / d0, 1e-9 * s.state.ks);
  EXPECT_NEAR(s.state.km, 10e9 * I / d0, 1e-9 * s.state.km);
  // Pulled by 1e-8 m: f_n = -K_n 1e-8 = -0.03927 N, a tension of E_b 1e-8 / d0 = 100 kPa.
  s.b.x.x += 1e-8;
  const PairResult r = s.evaluate();
  EXPECT_NEAR(r.f2.x, -10e9 * A / d0 * 1e-8, 1e-6 * 0.03927);
  EXPECT_NEAR(RicebalBond::energy(s.params, s.state, s.radii()).tension, 0.5 * s.state.kn * 1e-16,
              1e-9 * 2e-10);
  // A given G_b replaces the one from nu_b.
  PairStepper<RicebalBond> g;
  g.params.shear_modulus = 3e9;
  g.b.x = {2 * kR, 0, 0};
  g.install();
  EXPECT_NEAR(g.state.ks, 3e9 * A / d0, 1e-9 * g.state.ks);
}

TEST(RicebalBond, DisksTakeTheSlabOfTheirThickness) {
  // Disks (not planar spheres) of thickness t: A_b = 2 r_b t, I_b = 2/3 r_b^3 t, with r_b the
  // smaller radius (0.3 mm against 0.5 mm).
  PairStepper<RicebalBond> s;
  s.planar_sphere = false;
  s.thickness = 0.2e-3;
  s.b.R = 0.3e-3;
  s.b.x = {0.8e-3, 0, 0};
  s.install();
  EXPECT_NEAR(s.state.area, 2 * 0.3e-3 * 0.2e-3, 1e-20);
  EXPECT_NEAR(s.state.inertia, 2.0 / 3.0 * std::pow(0.3e-3, 3) * 0.2e-3, 1e-25);
  EXPECT_NEAR(s.state.kn, 10e9 * 1.2e-7 / 0.8e-3, 1e-3);
}

TEST(RicebalBond, ANormalSpringInTensionOnlyRestsAtTouching) {
  // Installed with the grains overlapping by 1e-7 m (d0 = 2R - 1e-7): the spring rests at
  // touching, so it pushes nothing while they overlap and pulls K_n (d - 2R) once apart; the
  // stiffness is still E_b A_b / d0. The default spring pulls from d0 at once.
  PairStepper<RicebalBond> s;
  s.params.normal_spring_in_compression = false;
  s.b.x = {2 * kR - 1e-7, 0, 0};
  s.install();
  const double kn = 10e9 * kPi * kR * kR / (2 * kR - 1e-7);
  EXPECT_NEAR(s.state.kn, kn, 1e-9 * kn);
  for (const double d : {2 * kR - 2e-7, 2 * kR - 0.5e-7, 2 * kR}) {
    s.b.x.x = d;
    s.evaluate();
    EXPECT_EQ(s.state.normal_force, 0.0) << d;
  }
  s.b.x.x = 2 * kR + 1e-8;
  s.evaluate();
  EXPECT_NEAR(s.state.normal_force, -kn * 1e-8, 1e-6 * kn * 1e-8);
  // Installed across a gap of 1e-8 m, it rests at the gap.
  auto gapped = touching_pair(1e-8);
  gapped.params.normal_spring_in_compression = false;
  gapped.install();
  gapped.evaluate();
  EXPECT_EQ(gapped.state.normal_force, 0.0);
  // The default (both ways) pushes back from d0 as soon as the overlapped pair is pressed.
  PairStepper<RicebalBond> both;
  both.b.x = {2 * kR - 1e-7, 0, 0};
  both.install();
  both.b.x.x = 2 * kR - 2e-7;
  both.evaluate();
  EXPECT_NEAR(both.state.normal_force, kn * 1e-7, 1e-6 * kn * 1e-7);
}

TEST(RicebalBond, ShearAndBendingSpringsFollowTheRelativeMotion) {
  // Grain 2 slides along +y by v dt per step and turns by w dt: after n steps (the first adds
  // nothing: the bond is new), f_s = -K_s (n - 1) v dt along y and M = -K_M (n - 1) w dt.
  auto s = touching_pair();
  s.b.v = {0, 1e-3, 0};
  s.b.w = {0, 0, 3.0};
  PairResult r;
  const int n = 50;
  for (int k = 0; k < n; ++k) {
    r = s.evaluate();
    s.move();
  }
  // The slide and the turn both move the contact point of grain 2: v + w R along y.
  const double slip = (n - 1) * (1e-3 - 3.0 * kR) * s.dt;
  EXPECT_NEAR(s.state.shear_force, -s.state.ks * slip, 1e-9 * s.state.ks * std::abs(slip));
  EXPECT_NEAR(r.couple.z, -s.state.km * (n - 1) * 3.0 * s.dt, 1e-9 * s.state.km * 1e-6);
  EXPECT_EQ(r.couple.x, 0.0);
  EXPECT_EQ(r.couple.y, 0.0);
}

TEST(RicebalBond, TensileCheckAddsTheMomentsPeakStress) {
  // f_n = -T A / 2 and a moment M with M r / I = T / 2: sigma_t = T exactly.
  auto s = touching_pair();
  const RicebalBond::Params p = s.params;
  const double A = s.state.area, I = s.state.inertia, T = p.tensile_strength;
  for (const double factor : {1 - 1e-9, 1 + 1e-9}) {
    RicebalBond::State st = s.state;
    st.normal_force = -0.5 * T * A;
    st.moment = -0.5 * T * I / kR * factor;
    BondFailure f;
    RicebalBond::judge(p, st, make_geometry(s.a, s.b, true, 1.0, true), {}, f);
    EXPECT_EQ(f.broken, factor > 1) << factor;
    if (f.broken) {
      EXPECT_EQ(f.mode, CrackMode::Tensile);
      EXPECT_NEAR(f.sigma, T * factor, 1e-6 * T);
      EXPECT_NEAR(f.Mb, 0.5 * T * I / kR * factor, 1e-9 * T * I / kR);
    }
  }
  // A moment factor beta takes beta of the bending stress: at beta = 0.5 the moment must double
  // to break the bond with the same f_n (sigma_t = T / 2 + 0.5 * 2 M r / I).
  RicebalBond::Params half = p;
  half.moment_factor = 0.5;
  for (const double factor : {1 - 1e-9, 1 + 1e-9}) {
    RicebalBond::State st = s.state;
    st.normal_force = -0.5 * T * A;
    st.moment = -T * I / kR * factor;
    BondFailure f;
    RicebalBond::judge(half, st, make_geometry(s.a, s.b, true, 1.0, true), {}, f);
    EXPECT_EQ(f.broken, factor > 1) << factor;
    if (f.broken) {
      EXPECT_NEAR(f.sigma, T * factor, 1e-6 * T);
    }
  }
  // Without the bending term (beta = 0) only f_n = -T A breaks the bond in tension, whatever
  // the moment.
  RicebalBond::Params no_bending = p;
  no_bending.moment_factor = 0.0;
  for (const double fn_factor : {0.5, 1 - 1e-9, 1 + 1e-9}) {
    RicebalBond::State st = s.state;
    st.normal_force = -fn_factor * T * A;
    st.moment = -0.5 * T * I / kR * (1 + 1e-9);
    BondFailure f;
    RicebalBond::judge(no_bending, st, make_geometry(s.a, s.b, true, 1.0, true), {}, f);
    EXPECT_EQ(f.broken, fn_factor > 1) << fn_factor;
    if (f.broken) {
      EXPECT_EQ(f.mode, CrackMode::Tensile);
    }
  }
}

TEST(RicebalBond, ShearStrengthFallsInTensionAndGrowsWithTheContactsCompression) {
  auto s = touching_pair();
  RicebalBond::Params p = s.params;
  const double A = s.state.area, C = p.cohesion, T = p.tensile_strength;
  const PairGeometry g = make_geometry(s.a, s.b, true, 1.0, true);
  auto breaks = [&](double fn_bond, double fs_bond, const Vec3& contact) {
    RicebalBond::State st = s.state;
    st.normal_force = fn_bond;
    st.shear_force = fs_bond;
    BondFailure f;
    RicebalBond::judge(p, st, g, contact, f);
    return f;
  };
  // Tension f_n = -T A / 2: f_s,max = C A (1 - 1/2).
  const double fs_t = 0.5 * C * A;
  EXPECT_FALSE(breaks(-0.5 * T * A, fs_t * (1 - 1e-9), {}).broken);
  const BondFailure ft = breaks(-0.5 * T * A, -fs_t * (1 + 1e-9), {});
  EXPECT_TRUE(ft.broken);
  EXPECT_EQ(ft.mode, CrackMode::Shear);
  EXPECT_NEAR(ft.ratio_s, 1 + 1e-9, 1e-12);
  // Compression from the contact alone (the bond unstretched): F_c = 10 N along n, and the
  // contact's own shear 2 N along t = z x n = +y. f_s,max = C A + mu 10 N.
  const double fs_c = C * A + p.friction * 10.0;
  const Vec3 contact{10.0, 2.0, 0.0};
  EXPECT_FALSE(breaks(0.0, fs_c * (1 - 1e-9) - 2.0, contact).broken);
  const BondFailure fc = breaks(0.0, fs_c * (1 + 1e-9) - 2.0, contact);
  EXPECT_TRUE(fc.broken);
  EXPECT_EQ(fc.mode, CrackMode::Shear);
  EXPECT_NEAR(fc.Fn, 10.0, 1e-12);
  EXPECT_NEAR(fc.Fs, fs_c * (1 + 1e-9), 1e-9);
  // The bond load that held with the contact's compression breaks the bond without it (its
  // strength is then C A = 31.4 N), and so does C A (1 + 1e-9) alone.
  EXPECT_TRUE(breaks(0.0, fs_c * (1 - 1e-9) - 2.0, {}).broken);
  EXPECT_FALSE(breaks(0.0, C * A * (1 - 1e-9), {}).broken);
  EXPECT_TRUE(breaks(0.0, C * A * (1 + 1e-9), {}).broken);
  // Judged on the bond's own loads, the contact changes nothing: the same bond load breaks it
  // with the contact pressing as without, at C A (1 + 1e-9), and holds at C A (1 - 1e-9).
  p.interface_totals = false;
  EXPECT_TRUE(breaks(0.0, fs_c * (1 - 1e-9) - 2.0, contact).broken);
  EXPECT_FALSE(breaks(0.0, C * A * (1 - 1e-9), contact).broken);
  const BondFailure own = breaks(0.0, C * A * (1 + 1e-9), contact);
  EXPECT_TRUE(own.broken);
  EXPECT_EQ(own.mode, CrackMode::Shear);
  EXPECT_NEAR(own.Fn, 0.0, 1e-12);
}

namespace {

// Two planar spheres pressed together by delta0 (Hertz-Mindlin contact), bonded in that state,
// then grain 2 driven along +y until the bond fails in shear.
Simulation sheared_pair(double delta0, double speed) {
  ParticleStore ps(Dimension::Two, 2 * kR, PlanarBody::PlanarSphere);
  ps.add({.tag = 1, .position = {}, .radius = kR, .density = 2650, .motion = Motion::Fixed});
  ps.add({.tag = 2,
          .position = {2 * kR - delta0, 0, 0},
          .radius = kR,
          .density = 2650,
          .velocity = {0, speed, 0},
          .motion = Motion::Driven});
  EngineConfig cfg;
  cfg.time_step = 1e-8;
  cfg.energy_interval = 0;
  HertzMindlin::Params hm;
  hm.shear_modulus = 10e9;
  hm.poisson_ratio = 0.2;
  hm.friction = 0.5;
  Simulation sim(std::move(ps), cfg, make_contact_model<HertzMindlin>(hm, hm));
  RicebalBond::Params p = RicebalBond::example_params();
  sim.set_bond_params<RicebalBond>(p);
  sim.add_bond<RicebalBond>(1, 2);
  sim.initialise();
  return sim;
}

}  // namespace

TEST(RicebalBond, TheEngineJudgesTheBondOnTheInterfaceTotals) {
  // delta0 = 20 um: the Hertz force 4/3 E* sqrt(R*) delta^1.5 = 23.6 N raises the shear strength
  // from C A = 31.4 N to about 43 N; the crack's F_n and F_s are the totals of bond and contact.
  const double delta0 = 20e-6, speed = 0.05;
  Simulation sim = sheared_pair(delta0, speed);
  for (int k = 0; k < 100000 && sim.cracks().empty(); ++k) sim.step();
  ASSERT_EQ(sim.cracks().size(), 1u);
  const CrackRecord& c = sim.cracks().front();
  EXPECT_EQ(c.mode, CrackMode::Shear);
  // The pair's geometry at the crack, from its normal (grain 2 moves along y only).
  const double x = 2 * kR - delta0, d = x / c.normal.x, delta = 2 * kR - d;
  const double E = 2 * 10e9 * 1.2, e_star = E / (2 * (1 - 0.04)), r_star = 0.5 * kR;
  const double hertz = 4.0 / 3.0 * e_star * std::sqrt(r_star) * std::pow(delta, 1.5);
  const double A = kPi * kR * kR, kn = 10e9 * A / x;
  const double fn = hertz + kn * (x - d);
  EXPECT_NEAR(c.Fn, fn, 1e-6 * fn);
  EXPECT_GT(hertz, 20.0);
  const RicebalBond::Params p = RicebalBond::example_params();
  const double fs_max = p.cohesion * A + p.friction * fn;
  // It breaks in the first step at or past the envelope: within one step's shear increment of
  // both springs (K_s + k_t) v dt (< 3e-3 N here).
  const double ks = p.shear_modulus_used * A / x;
  const double kt = 8 * 10e9 / (2 * 1.8) * std::sqrt(r_star * delta);
  EXPECT_GE(c.Fs, fs_max);
  EXPECT_LE(c.Fs - fs_max, (ks + kt) * speed * 1e-8);
  EXPECT_GT(fs_max, 1.3 * p.cohesion * A);
}

// ---- the 2D laboratory's inputs: planar spheres and their effective thickness (§3.4) ----

namespace {

constexpr const char* k2D =
    "[engine]\ndimension = 2\n[material]\npreset = \"custom\"\n[sample]\nshape = "
    "\"rectangle\"\nradius_min = 0.3e-3\nradius_max = 0.5e-3\n";

std::string error_of(const std::string& text) {
  try {
    parse_experiment(text, "lab.toml", {});
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

}  // namespace

TEST(PlanarSpheres, HertzContactsIn2DMakePlanarSpheresTwoMeanRadiiThick) {
  // Uniform radii 0.3-0.5 mm: R_bar = 0.4 mm, t_eff = 0.8 mm.
  const ExperimentSpec h =
      parse_experiment(std::string(k2D) + "[contact]\nlaw = \"hertz_mindlin\"\n", "lab.toml", {});
  EXPECT_EQ(h.planar_body, "planar_sphere");
  EXPECT_EQ(h.grain_body(), PlanarBody::PlanarSphere);
  EXPECT_NEAR(h.thickness, 0.8e-3, 1e-15);
  // The resolved file reads back to the same (the run manifest).
  const ExperimentSpec again = parse_experiment(to_toml(h), "resolved.toml", {});
  EXPECT_EQ(again.planar_body, "planar_sphere");
  EXPECT_EQ(again.thickness, h.thickness);
  // A given thickness is kept; linear contacts keep disks of the default 1 mm.
  EXPECT_EQ(parse_experiment(std::string(k2D) + "thickness = 2e-4\n[contact]\nlaw = "
                                                "\"hertz_mindlin\"\n",
                             "lab.toml", {})
                .thickness,
            2e-4);
  const ExperimentSpec d = parse_experiment(k2D, "lab.toml", {});
  EXPECT_EQ(d.planar_body, "disk");
  EXPECT_EQ(d.thickness, 1e-3);
  // A hexagonal lattice of planar spheres is one diameter thick.
  const ExperimentSpec lat = parse_experiment(
      "[engine]\ndimension = 2\n[sample]\nsource = \"lattice\"\nradius = 1e-4\nplanar_body = "
      "\"planar_sphere\"\n",
      "lab.toml", {});
  EXPECT_EQ(lat.thickness, 2e-4);
}

TEST(PlanarSpheres, ASampleFileGivesItsOwnThickness) {
  // A sample `breccia generate` wrote records its thickness; planar spheres read from it keep it.
  const auto path = std::filesystem::temp_directory_path() / "breccia_planar_sample.geom";
  std::ofstream(path) << "breccia-geometry 1\ndimension 2\nthickness 7e-05\nparticles 0\n";
  const ExperimentSpec f =
      parse_experiment("[engine]\ndimension = 2\n[sample]\nsource = \"file\"\nfile = \"" +
                           path.string() + "\"\n[contact]\nlaw = \"hertz_mindlin\"\n",
                       "lab.toml", {});
  EXPECT_EQ(f.thickness, 7e-05);
  std::filesystem::remove(path);
}

TEST(PlanarSpheres, RefusedCombinationsSayWhy) {
  const std::string disk_hertz =
      error_of(std::string(k2D) + "planar_body = \"disk\"\n[contact]\nlaw = \"hertz_mindlin\"\n");
  EXPECT_NE(disk_hertz.find("contact.law"), std::string::npos) << disk_hertz;
  EXPECT_NE(disk_hertz.find("planar_sphere"), std::string::npos) << disk_hertz;
  const std::string ricebal_3d = error_of("[bond]\nlaw = \"ricebal_bond\"\n");
  EXPECT_NE(ricebal_3d.find("bond.law"), std::string::npos) << ricebal_3d;
  EXPECT_NE(ricebal_3d.find("engine.dimension = 2"), std::string::npos) << ricebal_3d;
  const std::string file = error_of(
      "[engine]\ndimension = 2\n[sample]\nsource = \"table\"\nfile = \"x.txt\"\n[contact]\nlaw = "
      "\"hertz_mindlin\"\n");
  EXPECT_NE(file.find("sample.thickness"), std::string::npos) << file;
  EXPECT_NE(error_of(std::string(k2D) + "planar_body = \"sphere\"\n").find("planar_sphere"),
            std::string::npos);
}
