#pragma once
// What a packed and bonded sample looks like: porosity with overlap corrections (docs/physics.md
// §7.7), contact and bond coordination, floaters, and the profile in slices along the vessel's
// profile axis (Region::profile_axis: the loading axis, or a slab's longest side), bonds per grain
// and solid fraction per eighth, with the homogeneity check the sample bars use.
#include <cstdint>
#include <utility>
#include <vector>

#include "breccia/sample/region.hpp"
#include "breccia/state/particle_store.hpp"

namespace breccia {

struct ProfileSlice {
  double lo = 0.0, hi = 0.0;  // m, along the profile axis
  std::size_t grains = 0;     // centres within the slice
  double bonds_per_grain = 0.0;
  double solid_fraction = 0.0;  // solid volume inside the slice (spheres cut exactly) / slab volume
};

// Relative deviations of the profile (fractions, not percent). Interior: the slices other than the
// two end ones; ends: the first and the last slice.
struct HomogeneityCheck {
  double interior_bonds_spread = 0.0;  // max |slice - interior mean| / interior mean
  double interior_solid_spread = 0.0;
  double end_bonds_difference = 0.0;  // |first - last| / mean of the two
  double end_solid_difference = 0.0;
  double end_bonds_deficit = 0.0;  // max |end - interior mean| / interior mean
  double end_solid_deficit = 0.0;
  // The bars: interior within 3 %, ends within 3 % of each other and 8 % of the interior.
  static constexpr double kInteriorBar = 0.03, kEndPairBar = 0.03, kEndInteriorBar = 0.08;
  bool passes() const noexcept {
    return interior_bonds_spread <= kInteriorBar && interior_solid_spread <= kInteriorBar &&
           end_bonds_difference <= kEndPairBar && end_solid_difference <= kEndPairBar &&
           end_bonds_deficit <= kEndInteriorBar && end_solid_deficit <= kEndInteriorBar;
  }
};

struct SampleStructure {
  std::size_t particles = 0, bonds = 0;
  double porosity = 0.0;                     // vessel volume, lens-corrected
  double contact_coordination = 0.0;         // overlapping pairs per particle x 2
  double bond_coordination = 0.0;            // 2 bonds / particles
  double bonds_per_interior_particle = 0.0;  // centres > 2 r_max from every vessel wall
  int floater_contacts = 3;                  // N_f
  // Floaters as Potyondy & Cundall count them: fewer than N_f contacts, vessel walls included
  // (a grain in a corner with two bonds is held); and the stricter count of grains with fewer
  // than N_f bonds, which the floater placement works on (mostly grains at edges and corners).
  std::size_t floaters = 0;
  std::size_t few_bonds = 0;
  std::size_t unbonded = 0;  // particles with no bond at all
  int profile_axis = 2;      // 0, 1, 2: x, y, z
  std::vector<ProfileSlice> profile;
  HomogeneityCheck homogeneity;
};

// `bonds` are index pairs into `particles`; `gap_tolerance` is the bond gap tolerance (a wall
// within it counts as a contact).
SampleStructure describe_structure(
    const std::vector<PosRad>& particles,
    const std::vector<std::pair<std::uint32_t, std::uint32_t>>& bonds, const Region& region,
    double gap_tolerance, int floater_contacts, int slices = 8);

// The homogeneity numbers of a profile (at least three slices).
HomogeneityCheck check_homogeneity(const std::vector<ProfileSlice>& profile);

}  // namespace breccia
