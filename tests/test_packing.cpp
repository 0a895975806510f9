// Sample generation (docs/physics.md §7): the tangent fits of §7.4 against hand numbers, the
// expansion packing against the sample bars (floaters, homogeneity, locked-in stress from the
// test's own contact law), the insertion packing, and 2D preconsolidation.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <map>
#include <numbers>

#include "breccia/core/error.hpp"
#include "breccia/engine/neighbour_grid.hpp"
#include "breccia/engine/simulation.hpp"
#include "breccia/sample/geometry_file.hpp"
#include "breccia/sample/packing.hpp"
#include "breccia/sample/packing_methods.hpp"
#include "breccia/sample/structure.hpp"
#include "breccia/sample/tangent_fit.hpp"

namespace fs = std::filesystem;
using namespace breccia;

namespace {

Surface sphere(Vec3 c, double r) {
  return {false, c, {}, r};
}
Surface plane(Vec3 p, Vec3 n) {
  return {true, p, n, 0.0};
}

// A prism of about 2,000 grains, tall enough in grains for the eighth-by-eighth bars: 16 mean
// grain diameters across, 30 along the axis.
PackingSettings bar_prism() {
  PackingSettings s;
  s.width = s.depth = 5.2e-3;
  s.height = 9.75e-3;
  s.radii.r_min = 0.12e-3;
  s.radii.r_max = 0.2e-3;
  s.porosity = 0.37;
  s.bond_gap_tolerance = 2e-6;
  s.contact = make_contact_model<HertzMindlin>({.shear_modulus = 29e9, .poisson_ratio = 0.33},
                                               {.shear_modulus = 29e9, .poisson_ratio = 0.33});
  s.seed = 3;
  return s;
}

// Largest overlap of any two grains, relative to the smaller radius.
double largest_overlap(const GeometryData& g) {
  std::vector<PosRad> p;
  for (const ParticleSpec& q : g.particles) p.push_back({q.position, q.radius});
  PairList near;
  build_neighbour_pairs(p, 0.0, g.dimension == Dimension::Two, near);
  double worst = 0.0;
  for (std::size_t k = 0; k < near.size(); ++k) {
    const PosRad& a = p[near.first[k]];
    const PosRad& b = p[near.second[k]];
    worst = std::max(worst, (a.r + b.r - norm(b.x - a.x)) / std::min(a.r, b.r));
  }
  return worst;
}

}  // namespace

TEST(TangentFit, HoleOfFourTouchingSpheresAndThreeTouchingDisks) {
  // Four spheres of radius R at the corners of a regular tetrahedron of edge 2R: the sphere in
  // the hole has radius R (sqrt(6) / 2 - 1) = 0.2247 R and sits at the centroid.
  const double R = 1e-3, a = 2 * R;
  const Vec3 v[4] = {{0, 0, 0},
                     {a, 0, 0},
                     {a / 2, a * std::sqrt(3.0) / 2, 0},
                     {a / 2, a * std::sqrt(3.0) / 6, a * std::sqrt(2.0 / 3.0)}};
  const auto fits =
      fit_free_radius({sphere(v[0], R), sphere(v[1], R), sphere(v[2], R), sphere(v[3], R)}, false);
  ASSERT_FALSE(fits.empty());
  EXPECT_NEAR(fits.front().radius, R * (std::sqrt(6.0) / 2 - 1), 1e-12);
  const Vec3 centroid = (v[0] + v[1] + v[2] + v[3]) * 0.25;
  EXPECT_NEAR(norm(fits.front().centre - centroid), 0.0, 1e-12);
  // Three touching disks of radius R: the hole's circle has radius R (2 / sqrt(3) - 1).
  const auto disk = fit_free_radius({sphere(v[0], R), sphere(v[1], R), sphere(v[2], R)}, true);
  ASSERT_FALSE(disk.empty());
  EXPECT_NEAR(disk.front().radius, R * (2 / std::sqrt(3.0) - 1), 1e-12);
  // Against two touching disks and the line they rest on: r = R / 4 (Descartes, one curvature 0).
  const auto floor = fit_free_radius(
      {sphere({0, R, 0}, R), sphere({2 * R, R, 0}, R), plane({0, 0, 0}, {0, 1, 0})}, true);
  ASSERT_FALSE(floor.empty());
  EXPECT_NEAR(floor.front().radius, R / 4, 1e-12);
  EXPECT_NEAR(floor.front().centre.x, R, 1e-12);
  EXPECT_NEAR(floor.front().centre.y, R / 4, 1e-12);
  // A given radius against three spheres: every solution touches all three.
  const double r = 0.5 * R;
  const auto at = fit_fixed_radius({sphere(v[0], R), sphere(v[1], R), sphere(v[2], R)}, r, false,
                                   {a / 2, 0.5 * a, a});
  ASSERT_EQ(at.size(), 2u);
  for (const Vec3& x : at)
    for (int k = 0; k < 3; ++k) EXPECT_NEAR(norm(x - v[k]), R + r, 1e-12);
  EXPECT_GT(at.front().z, 0.0) << "nearest the hint first";
  // Collinear centres leave no unique hole: refused.
  EXPECT_TRUE(fit_free_radius({sphere({0, 0, 0}, R), sphere({2 * R, 0, 0}, R),
                               sphere({4 * R, 0, 0}, R), sphere({6 * R, 0, 0}, R)},
                              false)
                  .empty());
}

TEST(Structure, ProfileOfAKnownLatticeAndTheSlabVolumes) {
  // A sphere cut by two planes: the slab volumes add up to the sphere.
  const double r = 1e-3;
  const double whole = 4.0 / 3.0 * std::numbers::pi * r * r * r;
  EXPECT_NEAR(solid_in_slab(0, r, -1, 0, false, 1) + solid_in_slab(0, r, 0, 1, false, 1), whole,
              1e-18);
  EXPECT_NEAR(solid_in_slab(0, r, -r / 2, r / 2, false, 1),
              std::numbers::pi * (r * r * r - r * r * r / 12.0), 1e-18);
  EXPECT_NEAR(solid_in_slab(0, r, -2, 2, true, 0.5), std::numbers::pi * r * r * 0.5, 1e-18);
  // A simple cubic block of touching spheres, 4 x 4 x 8, bonded to its 6 neighbours: every
  // eighth holds one layer of 16 grains with 24 bonds inside it (3 per grain), and 2 axial bonds
  // per grain (1 in the end layers): 5 bonds per grain inside, 4 at the ends.
  Region box;
  box.lx = box.ly = 4 * 2 * r;
  box.lz = 8 * 2 * r;
  std::vector<PosRad> p;
  for (int k = 0; k < 8; ++k)
    for (int j = 0; j < 4; ++j)
      for (int i = 0; i < 4; ++i)
        p.push_back({{(2 * i + 1) * r, (2 * j + 1) * r, (2 * k + 1) * r}, r});
  auto at = [](int i, int j, int k) { return static_cast<std::uint32_t>((k * 4 + j) * 4 + i); };
  std::vector<std::pair<std::uint32_t, std::uint32_t>> bonds;
  for (int k = 0; k < 8; ++k)
    for (int j = 0; j < 4; ++j)
      for (int i = 0; i < 4; ++i) {
        if (i < 3) bonds.emplace_back(at(i, j, k), at(i + 1, j, k));
        if (j < 3) bonds.emplace_back(at(i, j, k), at(i, j + 1, k));
        if (k < 7) bonds.emplace_back(at(i, j, k), at(i, j, k + 1));
      }
  const SampleStructure s = describe_structure(p, bonds, box, 1e-9, 3);
  ASSERT_EQ(s.profile.size(), 8u);
  // In-layer bonds per grain: 2 x 24 / 16 = 3; plus 2 axial (1 at the ends).
  EXPECT_DOUBLE_EQ(s.profile[0].bonds_per_grain, 4.0);
  EXPECT_DOUBLE_EQ(s.profile[3].bonds_per_grain, 5.0);
  EXPECT_DOUBLE_EQ(s.profile[7].bonds_per_grain, 4.0);
  // Solid fraction of a simple cubic packing: pi / 6 in every layer.
  for (const ProfileSlice& sl : s.profile)
    EXPECT_NEAR(sl.solid_fraction, std::numbers::pi / 6, 1e-12);
  EXPECT_NEAR(s.porosity, 1 - std::numbers::pi / 6, 1e-12);
  EXPECT_DOUBLE_EQ(s.homogeneity.interior_bonds_spread, 0.0);
  EXPECT_DOUBLE_EQ(s.homogeneity.end_bonds_difference, 0.0);
  EXPECT_DOUBLE_EQ(s.homogeneity.end_bonds_deficit, 0.2);
  EXPECT_FALSE(s.homogeneity.passes()) << "the ends of a 4-grain-wide block lose 20 %";
  // Corner grains touch three walls; none is a floater.
  EXPECT_EQ(s.floaters, 0u);
}

TEST(Packing, ASlabIsProfiledAlongItsLongestSide) {
  // The profile runs along the loading axis unless a box is longer across it: eighths of a 5 mm
  // slab's thickness would be thinner than its grains.
  Region slab;
  slab.lx = slab.ly = 0.030;
  slab.lz = 0.005;
  EXPECT_EQ(slab.profile_axis(), 0);
  EXPECT_DOUBLE_EQ(slab.profile_length(), 0.030);
  Region narrow = slab;
  narrow.lx = 0.010;
  EXPECT_EQ(narrow.profile_axis(), 1);
  Region column = slab;
  column.lz = 0.060;
  EXPECT_EQ(column.profile_axis(), 2);
  Region cube = slab;
  cube.lz = 0.030;
  EXPECT_EQ(cube.profile_axis(), 2) << "a tie keeps the loading axis";
  Region wide{SampleShape::Rectangle, 0.030, 0.005, 0.0, 0.0, 1e-3};
  EXPECT_EQ(wide.profile_axis(), 0);
  Region cylinder{SampleShape::Cylinder, 0.0, 0.0, 0.010, 0.020, 1.0};
  EXPECT_EQ(cylinder.profile_axis(), 2) << "round vessels keep their axis";
  EXPECT_NEAR(slab.slab_volume(0.0, 0.030), slab.volume(), 1e-18);
  EXPECT_NEAR(slab.slab_volume(0.0, 0.003), 0.003 * 0.030 * 0.005, 1e-18);

  // A simple cubic slab of touching spheres, 8 x 4 x 2 grains, bonded to its 6 neighbours: each
  // eighth along x is one layer of 8 grains with 10 bonds inside it (2.5 per grain) and 2 bonds
  // per grain along x (1 in the end layers): 4.5 bonds per grain inside, 3.5 at the ends.
  const double r = 1e-3;
  Region box;
  box.lx = 8 * 2 * r;
  box.ly = 4 * 2 * r;
  box.lz = 2 * 2 * r;
  std::vector<PosRad> p;
  for (int k = 0; k < 2; ++k)
    for (int j = 0; j < 4; ++j)
      for (int i = 0; i < 8; ++i)
        p.push_back({{(2 * i + 1) * r, (2 * j + 1) * r, (2 * k + 1) * r}, r});
  auto at = [](int i, int j, int k) { return static_cast<std::uint32_t>((k * 4 + j) * 8 + i); };
  std::vector<std::pair<std::uint32_t, std::uint32_t>> bonds;
  for (int k = 0; k < 2; ++k)
    for (int j = 0; j < 4; ++j)
      for (int i = 0; i < 8; ++i) {
        if (i < 7) bonds.emplace_back(at(i, j, k), at(i + 1, j, k));
        if (j < 3) bonds.emplace_back(at(i, j, k), at(i, j + 1, k));
        if (k < 1) bonds.emplace_back(at(i, j, k), at(i, j, k + 1));
      }
  const SampleStructure s = describe_structure(p, bonds, box, 1e-9, 3);
  EXPECT_EQ(s.profile_axis, 0);
  ASSERT_EQ(s.profile.size(), 8u);
  EXPECT_DOUBLE_EQ(s.profile[0].lo, 0.0);
  EXPECT_DOUBLE_EQ(s.profile[7].hi, 16 * r);
  for (const ProfileSlice& sl : s.profile) {
    EXPECT_EQ(sl.grains, 8u);
    EXPECT_NEAR(sl.solid_fraction, std::numbers::pi / 6, 1e-12);
  }
  EXPECT_DOUBLE_EQ(s.profile[0].bonds_per_grain, 3.5);
  EXPECT_DOUBLE_EQ(s.profile[4].bonds_per_grain, 4.5);
  EXPECT_DOUBLE_EQ(s.profile[7].bonds_per_grain, 3.5);
  EXPECT_NEAR(s.homogeneity.end_bonds_deficit, 1.0 / 4.5, 1e-12);
}

// The servo's "arrived" rule on readings around a goal of 100 (tolerance 2 %, spread 5 %): a
// noisy series whose mean sits at the goal arrives although no five readings in a row are within
// 2 %; a series biased 3 % low, one reading past the spread, or a last reading past the
// tolerance does not; nothing arrives before five readings.
TEST(Packing, StressWindowJudgesTheLastFiveReadings) {
  auto arrives = [](std::vector<double> readings) {
    packing::StressWindow w(100.0, 0.02, 0.05);
    bool at = false;
    for (double p : readings) at = w.push(p);
    return at;
  };
  EXPECT_TRUE(arrives({104, 96.5, 103.5, 97, 100}));     // mean 100.2, last within 2 %
  EXPECT_FALSE(arrives({100, 100, 100, 100}));           // four readings only
  EXPECT_FALSE(arrives({97, 97, 97, 97, 97}));           // mean 3 % low
  EXPECT_FALSE(arrives({106, 99, 99, 99, 99}));          // one reading past the 5 % spread
  EXPECT_FALSE(arrives({100, 100, 100, 102.5, 97.4}));   // last reading 2.6 % off
  EXPECT_TRUE(arrives({150, 100, 100, 100, 100, 100}));  // the old reading has left the window
}

TEST(Packing, ExpansionMeetsTheSampleBars) {
  const PackingSettings s = bar_prism();
  const PackedSample p = pack_sample(s);
  const PackingReport& r = p.report;
  const SampleStructure& st = r.structure;
  EXPECT_TRUE(r.converged);
  // The servo stops with p and the mean of its last 5 checks within 2 % of p0 while the grains
  // still move; the stress recomputed with the grains at rest is within another percent
  // (floaters are placed touching without overlap, which changes no force).
  EXPECT_NEAR(r.locked_in_mean_stress, s.isotropic_stress, 0.03 * s.isotropic_stress);
  // Floaters: at most 1 % of the grains with fewer than 3 contacts; fewer than 3 bonds only at
  // edges and corners, 2 % at most in a sample this small.
  EXPECT_LE(static_cast<double>(st.floaters), 0.01 * static_cast<double>(st.particles));
  EXPECT_LE(static_cast<double>(st.few_bonds), 0.02 * static_cast<double>(st.particles));
  EXPECT_LE(r.largest_floater_growth, s.floater_max_growth + 1e-9);
  // Dense: a frictionless packing of spheres with R_max / R_min = 1.67 in a vessel this size.
  EXPECT_GT(st.porosity, 0.34);
  EXPECT_LT(st.porosity, 0.42);
  EXPECT_GT(st.bonds_per_interior_particle, 5.0);
  // Homogeneity bars (issue: interior eighths within 3 %, ends within 3 % of each other and 8 %
  // of the interior), bonds per grain and solid fraction.
  const HomogeneityCheck& h = st.homogeneity;
  EXPECT_TRUE(h.passes()) << "interior " << h.interior_bonds_spread << " / "
                          << h.interior_solid_spread << ", ends " << h.end_bonds_difference << " / "
                          << h.end_solid_difference << ", end deficit " << h.end_bonds_deficit
                          << " / " << h.end_solid_deficit;
  // No two grains overlap by more than a Hertz contact at a few times p0 allows.
  EXPECT_LT(largest_overlap(p.geometry), 0.01);
  // Every grain inside the vessel, up to the overlap of its wall contact.
  for (const ParticleSpec& q : p.geometry.particles) {
    EXPECT_GE(q.position.x - q.radius, -0.01 * q.radius);
    EXPECT_LE(q.position.z + q.radius, s.height + 0.01 * q.radius);
  }
}

TEST(Packing, LockedInStressIsTheTestContactLaws) {
  // Packed with the test's Hertz law: the stress its contacts carry in a simulation built from
  // the written sample with that law is the one the report gives.
  PackingSettings s = bar_prism();
  s.width = s.depth = 3e-3;
  s.height = 4e-3;
  s.seed = 5;
  const PackedSample p = pack_sample(s);
  ParticleStore store = p.geometry.make_store();
  EngineConfig cfg;
  Simulation sim(std::move(store), cfg, s.contact);
  sim.initialise();
  sim.step();  // the pair forces of the packed positions (nothing moves before they are computed)
  const double volume = s.width * s.depth * s.height;
  const PairStress ps = sim.pair_stress();
  EXPECT_NEAR(ps.mean(3, volume), p.report.locked_in_mean_stress,
              1e-6 * p.report.locked_in_mean_stress);
  EXPECT_NEAR(ps.lf[8] / volume, p.report.locked_in_zz, 1e-6 * p.report.locked_in_mean_stress);
  EXPECT_EQ(p.report.contact_law, "hertz_mindlin");
  // The same packing with linear contacts is another sample: its stress is its own law's.
  PackingSettings lin = s;
  lin.contact = make_contact_model<LinearContact>({}, {});
  const PackedSample q = pack_sample(lin);
  EXPECT_EQ(q.report.contact_law, "linear");
  EXPECT_NEAR(q.report.locked_in_mean_stress, s.isotropic_stress, 0.03 * s.isotropic_stress);
}

TEST(Packing, SameSeedSameSampleAndItRoundTrips) {
  PackingSettings s = bar_prism();
  s.width = s.depth = 2.5e-3;
  s.height = 3e-3;
  const PackedSample a = pack_sample(s), b = pack_sample(s);
  ASSERT_EQ(a.geometry.particles.size(), b.geometry.particles.size());
  for (std::size_t i = 0; i < a.geometry.particles.size(); ++i)
    EXPECT_EQ(a.geometry.particles[i].position.x, b.geometry.particles[i].position.x);
  EXPECT_EQ(a.geometry.bonds, b.geometry.bonds);
  const fs::path file = fs::temp_directory_path() / "breccia_packing_roundtrip.geom";
  write_geometry(file.string(), a.geometry);
  const GeometryData back = read_geometry(file.string());
  ASSERT_EQ(back.particles.size(), a.geometry.particles.size());
  for (std::size_t i = 0; i < back.particles.size(); ++i) {
    EXPECT_EQ(back.particles[i].position.y, a.geometry.particles[i].position.y);
    EXPECT_EQ(back.particles[i].radius, a.geometry.particles[i].radius);
  }
  EXPECT_EQ(back.bonds, a.geometry.bonds);
  fs::remove(file);
}

TEST(Packing, CylinderDiskAndRectanglePack) {
  PackingSettings c = bar_prism();
  c.shape = SampleShape::Cylinder;
  c.diameter = 3e-3;
  c.height = 3e-3;
  c.servo_to_stress = false;  // porosity mode: packed at the target, whatever stress results
  c.porosity = 0.41;
  const PackedSample pc = pack_sample(c);
  // The target porosity less the overlaps of the contacts (lens corrections).
  EXPECT_NEAR(pc.report.structure.porosity, c.porosity, 0.005);
  // Denser than this small cylinder jams, so the walls press in: overlaps of a few % of a radius.
  for (const ParticleSpec& q : pc.geometry.particles)
    EXPECT_LE(std::hypot(q.position.x, q.position.y) + q.radius, 1.5e-3 + 0.05 * q.radius);
  EXPECT_LE(static_cast<double>(pc.report.structure.floaters),
            0.01 * static_cast<double>(pc.report.structure.particles));
  PackingSettings r = bar_prism();
  r.shape = SampleShape::Rectangle;
  r.width = 4e-3;
  r.height = 6e-3;
  r.thickness = 0.4e-3;
  r.porosity = 0.16;
  r.contact = make_contact_model<LinearContact>({}, {});
  const PackedSample pr = pack_sample(r);
  EXPECT_EQ(pr.geometry.dimension, Dimension::Two);
  for (const ParticleSpec& q : pr.geometry.particles) EXPECT_EQ(q.position.z, 0.0);
  EXPECT_NEAR(pr.report.locked_in_mean_stress, r.isotropic_stress, 0.03 * r.isotropic_stress);
  EXPECT_LE(static_cast<double>(pr.report.structure.floaters),
            0.01 * static_cast<double>(pr.report.structure.particles));
  // From the 3D-minded porosity 0.37 (looser than jammed disks): grown on until jammed.
  r.porosity = 0.37;
  const PackedSample loose = pack_sample(r);
  EXPECT_TRUE(loose.report.converged);
  EXPECT_LT(loose.report.structure.porosity, 0.25);
  // A 2D disk (the Brazilian disc).
  PackingSettings d = r;
  d.shape = SampleShape::Disk;
  d.diameter = 5e-3;
  d.porosity = 0.16;
  const PackedSample pd = pack_sample(d);
  for (const ParticleSpec& q : pd.geometry.particles)
    EXPECT_LE(std::hypot(q.position.x, q.position.y) + q.radius, 2.5e-3 + 0.01 * q.radius);
  EXPECT_GT(pd.report.structure.bond_coordination, 3.0);
}

TEST(Packing, InsertionIsDenseStressFreeAndWithinItsBounds) {
  PackingSettings s = bar_prism();
  s.method = PackingMethod::Insertion;
  s.width = s.depth = 3e-3;
  s.height = 4e-3;
  s.radii.r_min = 0.08e-3;  // GenGeo-style wide range
  s.radii.r_max = 0.2e-3;
  s.insertion_failures = 2000;
  s.bond_gap_tolerance = 1e-3 * s.radii.r_min;  // docs/physics.md §7.6 for geometric packings
  const PackedSample p = pack_sample(s);
  const SampleStructure& st = p.report.structure;
  for (const ParticleSpec& q : p.geometry.particles) {
    EXPECT_GE(q.radius, s.radii.r_min);
    EXPECT_LE(q.radius, s.radii.r_max);
  }
  EXPECT_LT(largest_overlap(p.geometry), 1e-8) << "fitted grains touch, they do not overlap";
  EXPECT_LT(std::abs(p.report.locked_in_mean_stress), 1.0) << "Pa: touching, round-off aside";
  EXPECT_LT(st.porosity, 0.45);
  EXPECT_GT(st.bond_coordination, 4.0) << "every fitted grain touches D + 1 others";
  const PackedSample again = pack_sample(s);
  EXPECT_EQ(again.geometry.bonds, p.geometry.bonds);
}

namespace {

// A 2.5 x 4 mm rectangle preconsolidated to 10 MPa at porosity 0.18, without bonds.
PackingSettings preconsolidated_rectangle() {
  PackingSettings s;
  s.method = PackingMethod::Preconsolidation;
  s.shape = SampleShape::Rectangle;
  s.width = 2.5e-3;
  s.height = 4e-3;
  s.porosity = 0.18;
  s.preconsolidation_stress = 10e6;
  s.bond_gap_tolerance = 0.0;
  return s;
}

}  // namespace

TEST(Packing, PreconsolidationReachesItsStressIn2D) {
  PackingSettings s = preconsolidated_rectangle();
  s.thickness = 0.1e-3;
  s.radii.r_min = 10e-6 * 2;  // seed 002's 10-40 um, doubled to keep the test small
  s.radii.r_max = 40e-6 * 2;
  s.contact = make_contact_model<LinearContact>({.modulus = 20e9}, {.modulus = 20e9});
  const PackedSample p = pack_sample(s);
  EXPECT_TRUE(p.report.converged);
  ASSERT_FALSE(p.report.stages.empty());
  // The side rows carry 10 MPa within 2 % (the servo's stopping rule); the locked-in mean stress
  // of the sample's own contacts is of that order.
  EXPECT_NEAR(p.report.preconsolidation_stress_reached, 10e6, 0.02 * 10e6);
  EXPECT_GT(p.report.locked_in_mean_stress, 5e6);
  EXPECT_LT(p.report.structure.porosity, 0.22);
  EXPECT_GT(p.report.structure.porosity, 0.10);
  // Compacted across the loading axis: narrower than the loose box, as tall as asked.
  EXPECT_LT(p.report.width, s.width * (1 - s.porosity) / 0.45);
  EXPECT_DOUBLE_EQ(p.report.height, s.height);
  for (const ParticleSpec& q : p.geometry.particles) {
    EXPECT_GE(q.position.y - q.radius, -0.3 * s.radii.r_min);
    EXPECT_LE(q.position.y + q.radius, s.height + 0.3 * s.radii.r_min);
  }
}

TEST(Packing, HomogeneousCompactionReachesItsStressIn2D) {
  // The sample strained with its side rows (docs/physics.md §7.3): the rows carry 10 MPa and the
  // sample's own contacts balance them, its grains as evenly packed along the height as the
  // rows' (homogeneity), and the width shrinks by the compaction.
  PackingSettings s = preconsolidated_rectangle();
  s.thickness = 0.1e-3;
  s.radii.r_min = 20e-6;
  s.radii.r_max = 80e-6;
  s.contact = make_contact_model<LinearContact>({.modulus = 20e9}, {.modulus = 20e9});
  s.homogeneous_compaction = true;
  s.bond_gap_tolerance = 0.2e-6;  // bonded, for the homogeneity's bonds per grain
  const PackedSample p = pack_sample(s);
  EXPECT_TRUE(p.report.converged) << p.report.stages.back().note;
  EXPECT_NEAR(p.report.preconsolidation_stress_reached, 10e6, 0.02 * 10e6);
  EXPECT_GT(p.report.locked_in_mean_stress, 5e6);
  EXPECT_LT(p.report.structure.porosity, 0.22);
  EXPECT_GT(p.report.structure.porosity, 0.10);
  EXPECT_LT(p.report.width, s.width * (1 - s.porosity) / 0.45);
  // Homogeneity, with the bars widened by counting noise: a slice's bonds per grain is a mean
  // over its n grains and scatters by sd / sqrt(n) with no gradient at all (sd: the spread of the
  // grains' own bond counts). On this ~1,000-disk sample that is about 3 %, the size of the bar
  // itself, so a slice may miss the bar by two standard errors of the thinnest slice before the
  // test calls it a gradient (the solid fraction scatters less and keeps its bar).
  const HomogeneityCheck& h = p.report.structure.homogeneity;
  std::map<std::uint64_t, double> bonds_of;
  for (const auto& [a, b] : p.geometry.bonds) {
    bonds_of[a] += 1.0;
    bonds_of[b] += 1.0;
  }
  double sum = 0.0, sum2 = 0.0;
  for (const ParticleSpec& q : p.geometry.particles) {
    const double nb = bonds_of.contains(q.tag) ? bonds_of[q.tag] : 0.0;
    sum += nb;
    sum2 += nb * nb;
  }
  const double count = static_cast<double>(p.geometry.particles.size());
  const double mean = sum / count, sd = std::sqrt(sum2 / count - mean * mean);
  std::size_t thinnest = p.geometry.particles.size();
  for (const ProfileSlice& slice : p.report.structure.profile)
    thinnest = std::min(thinnest, slice.grains);
  ASSERT_GT(thinnest, 50u);
  const double noise = 2.0 * sd / mean / std::sqrt(static_cast<double>(thinnest));
  EXPECT_LE(h.interior_bonds_spread, HomogeneityCheck::kInteriorBar + noise) << noise;
  EXPECT_LE(h.end_bonds_difference, HomogeneityCheck::kEndPairBar + noise) << noise;
  EXPECT_LE(h.end_bonds_deficit, HomogeneityCheck::kEndInteriorBar + noise) << noise;
  EXPECT_LE(h.interior_solid_spread, HomogeneityCheck::kInteriorBar);
  EXPECT_LE(h.end_solid_difference, HomogeneityCheck::kEndPairBar);
  EXPECT_LE(h.end_solid_deficit, HomogeneityCheck::kEndInteriorBar);
  // The same sample with its side rows pushed alone waits at every check for the stress wave to
  // cross it: its compaction stage takes more steps (1.9x on 3,444 disks, 4.3x on 13,706).
  s.homogeneous_compaction = false;
  const PackedSample rows = pack_sample(s);
  ASSERT_EQ(rows.report.stages.at(1).name, "preconsolidation");
  ASSERT_EQ(p.report.stages.at(1).name, "preconsolidation");
  EXPECT_LT(p.report.stages[1].steps, rows.report.stages[1].steps)
      << p.report.stages[1].steps << " steps against the rows' " << rows.report.stages[1].steps;
}

TEST(Packing, BadSettingsAreRefused) {
  PackingSettings s = bar_prism();
  s.width = 0.5e-3;  // narrower than 4 grains
  EXPECT_THROW(pack_sample(s), InputError);
  s = bar_prism();
  s.porosity = 1.5;
  EXPECT_THROW(pack_sample(s), InputError);
  s = bar_prism();
  s.method = PackingMethod::Preconsolidation;  // a 2D procedure
  EXPECT_THROW(pack_sample(s), InputError);
}

TEST(Packing, PreconsolidationOfHertzPlanarSpheresHoldsItsStress) {
  // RICEBAL's grains (docs/physics.md §3.4, §7.3): planar spheres with Hertz-Mindlin contacts,
  // whose stiffness grows with the load; the row servo's gain comes from the stiffness at the
  // target load (from the stiffness at first touch the rows raced and never settled).
  PackingSettings s = preconsolidated_rectangle();
  s.radii.r_min = 20e-6;
  s.radii.r_max = 80e-6;
  s.thickness = 2 * 50e-6;  // t_eff = 2 R_bar
  s.planar_body = PlanarBody::PlanarSphere;
  HertzMindlin::Params hm;
  hm.shear_modulus = 10e9;
  hm.poisson_ratio = 0.2;
  s.contact = make_contact_model<HertzMindlin>(hm, hm);
  const PackedSample p = pack_sample(s);
  EXPECT_TRUE(p.report.converged) << p.report.stages.back().note;
  EXPECT_NEAR(p.report.preconsolidation_stress_reached, 10e6, 0.02 * 10e6);
  EXPECT_GT(p.report.locked_in_mean_stress, 5e6);
  EXPECT_EQ(p.report.contact_law, "hertz_mindlin");
}
