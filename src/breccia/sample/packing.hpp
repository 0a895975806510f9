#pragma once
// Dense random packings by radius expansion in a rigid vessel (physics.md §7.2, the PFC /
// Potyondy & Cundall 2004 material genesis): draw radii for a target porosity, place them shrunk
// at random without overlap, grow them to size frictionless while cycling with strong damping and
// relax; then either servo all radii to a target isotropic stress with friction on (default, low
// locked-in stress) or keep the target porosity. Finally every pair with a gap within the
// tolerance is bonded (§7.6).
#include <cstdint>
#include <functional>
#include <string>

#include "breccia/io/geometry_file.hpp"
#include "breccia/sample/radius_distribution.hpp"

namespace breccia {

enum class SampleShape { Prism, Cylinder, Rectangle };

struct PackingSettings {
  SampleShape shape = SampleShape::Prism;
  // Prism: width (x), depth (y), height (z); cylinder: diameter and height (axis z);
  // rectangle (2D): width (x) and height (y). Lowest corner (or the axis foot) at the origin.
  double width = 0.0, depth = 0.0, height = 0.0, diameter = 0.0;
  double thickness = 1.0;  // 2D disk thickness
  RadiusDistribution radii;
  double density = 2650.0;
  double porosity = 0.36;                // target porosity: fixes the particle count
  bool servo_to_stress = true;           // true: servo to isotropic_stress; false: porosity only
  double isotropic_stress = 0.1e6;       // Pa, p0 of §7.2 (low: about 1 % of the UCS or less)
  double contact_modulus = 10e9;         // Pa, E_c of the linear packing contacts
  double contact_stiffness_ratio = 2.5;  // k_n / k_s
  double servo_friction = 0.5;           // contact friction while servoing to p0
  double bond_gap_tolerance = 0.0;       // m, bond pairs with gap <= this
  std::uint64_t seed = 1;
  std::size_t max_particles = 2'000'000;
  std::uint64_t max_steps = 400'000;  // cycling limit of the whole packing
};

struct PackingReport {
  std::size_t particles = 0, bonds = 0;
  double porosity = 0.0;                    // with lens corrections (§7.7)
  double mean_coordination = 0.0;           // contacts per particle, all particles
  double bond_coordination_interior = 0.0;  // bonds per particle, > 2 r_max from the walls
  double locked_in_mean_stress = 0.0;       // Pa, trace/D of the pair-force stress (§6.5)
  double locked_in_xx = 0.0, locked_in_yy = 0.0, locked_in_zz = 0.0;
  double radius_mean = 0.0, radius_sd = 0.0, radius_min = 0.0, radius_max = 0.0;
  std::size_t floaters = 0;  // particles with fewer than 3 contacts (reported, not removed)
  std::uint64_t steps = 0;
  bool converged = false;
  double wall_seconds = 0.0;
  double volume = 0.0;  // vessel volume (2D: area x thickness)
  // Vessel size (the requested one): width (x, or diameter), depth (y, or diameter; 0 in 2D),
  // height (z, or y in 2D).
  double width = 0.0, depth = 0.0, height = 0.0;
};

struct PackedSample {
  GeometryData geometry;
  PackingReport report;
};

// Throws InputError on bad settings (named by key), or when particles cannot be placed.
PackedSample pack_sample(const PackingSettings& settings,
                         const std::function<void(const std::string&)>& log = {});

const char* shape_name(SampleShape s);

}  // namespace breccia
