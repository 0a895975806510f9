#pragma once
// Synthetic rock samples (docs/physics.md §7): a packing of spheres (3D) or disks (2D) in a vessel,
// then bonds between every pair with a gap within the tolerance (§7.6). Three ways to pack:
//
//  - expansion (default; PFC / Potyondy & Cundall 2004 material genesis, §7.2): radii drawn for a
//    target porosity, placed shrunk at random, grown frictionless in a rigid vessel, servoed to a
//    low isotropic stress (or held at the target porosity), floaters grown until they have N_f
//    contacts;
//  - insertion (GenGeo / Place & Mora style, §7.4): no dynamics, every new grain is fitted tangent
//    to its neighbours and the vessel; dense, stress-free, radii emergent within [r_min, r_max];
//  - preconsolidation (2D, RICEBAL practice, §7.3, seed 002): disks between particle-row walls,
//    the rows pushed in by servos until the sample carries a given stress (10 MPa), bonded in that
//    state; the test then unloads it, leaving the locked-in stress of a cemented rock.
//
// The packing cycles with the contact law the test will use (friction off), so the locked-in
// stress it reports is what the test starts from. How the samples are kept homogeneous is told in
// ARCHITECTURE.md ("Samples").
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "breccia/engine/simulation.hpp"
#include "breccia/sample/geometry_file.hpp"
#include "breccia/sample/radius_distribution.hpp"
#include "breccia/sample/region.hpp"
#include "breccia/sample/structure.hpp"

namespace breccia {

enum class PackingMethod { Expansion, Insertion, Preconsolidation };

struct PackingSettings {
  SampleShape shape = SampleShape::Prism;
  // Prism: width (x), depth (y), height (z); cylinder: diameter and height (axis z);
  // rectangle (2D): width (x) and height (y). Lowest corner (or the axis foot) at the origin.
  double width = 0.0, depth = 0.0, height = 0.0, diameter = 0.0;
  double thickness = 1.0;  // 2D thickness (disks), or planar spheres' effective thickness
  PlanarBody planar_body = PlanarBody::Disk;  // 2D grain mass and inertia (docs/physics.md §3.4)
  RadiusDistribution radii;
  double density = 2650.0;
  PackingMethod method = PackingMethod::Expansion;
  double porosity = 0.36;           // expansion: fixes the particle count
  bool servo_to_stress = true;      // expansion: true: servo to isotropic_stress; false: porosity
  double isotropic_stress = 0.1e6;  // Pa, p0 of §7.2 (low: about 1 % of the UCS or less)
  double preconsolidation_stress = 10e6;  // Pa, 2D preconsolidation (seed 002: 10 MPa)
  // 2D preconsolidation: the sample strained homogeneously with its side rows (steps about
  // independent of the width), instead of the side rows pushed in alone (docs/physics.md §7.3).
  bool homogeneous_compaction = false;
  // Contact law of the packing: the test's law and parameters (friction is switched off while
  // packing). Defaults to linear contacts with E_c = 10 GPa.
  ContactModel contact = make_contact_model<LinearContact>({}, {});
  double bond_gap_tolerance = 0.0;  // m, bond pairs with gap <= this
  int floater_contacts = 3;         // N_f: grains with fewer contacts are grown (expansion)
  double floater_max_growth = 0.2;  // largest relative radius growth of a floater (P&C: 20 %)
  std::uint64_t seed = 1;
  // The packing's kernels (core/instruction_set.hpp); none = the best this CPU runs.
  std::optional<InstructionSet> instruction_set;
  std::size_t max_particles = 2'000'000;
  std::uint64_t max_steps = 400'000;         // cycling limit of the whole packing
  std::uint64_t insertion_failures = 5'000;  // insertion: consecutive failed fits that end it
};

struct PackingStage {
  std::string name;
  std::uint64_t steps = 0;
  double seconds = 0.0;
  std::string note;
};

struct PackingReport {
  std::string method;  // "expansion", "insertion", "preconsolidation"
  std::string contact_law;
  SampleStructure structure;  // porosity, coordination, floaters, profile, homogeneity
  // Stress carried by the contacts in the packed state, from the test's contact law (§6.5),
  // compression-positive, over the vessel volume. Bonds are installed stress-free on top of it.
  double locked_in_mean_stress = 0.0;
  double locked_in_xx = 0.0, locked_in_yy = 0.0, locked_in_zz = 0.0;
  double radius_mean = 0.0, radius_sd = 0.0, radius_min = 0.0, radius_max = 0.0;
  double preconsolidation_stress_reached = 0.0;  // Pa, on the side rows (preconsolidation)
  std::size_t floaters_grown = 0;       // expansion: floaters enlarged (each at most by the cap)
  double largest_floater_growth = 0.0;  // relative
  std::uint64_t steps = 0;
  bool converged = false;
  double wall_seconds = 0.0;
  double volume = 0.0;  // vessel volume (2D: area x thickness)
  // Vessel size (the requested one, or after preconsolidation the compacted one): width (x, or
  // diameter), depth (y, or diameter; 0 in 2D), height (z, or y in 2D).
  double width = 0.0, depth = 0.0, height = 0.0;
  std::vector<PackingStage> stages;
  std::vector<std::string> warnings;
};

struct PackedSample {
  GeometryData geometry;
  PackingReport report;
};

// Throws InputError on bad settings (named by key), or when particles cannot be placed.
PackedSample pack_sample(const PackingSettings& settings,
                         const std::function<void(const std::string&)>& log = {});

const char* shape_name(SampleShape s);
const char* method_name(PackingMethod m);
// The vessel of the settings.
Region packing_region(const PackingSettings& s);

}  // namespace breccia
