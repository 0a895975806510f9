#pragma once
// Where the microcracks of a test lie: their share in each quarter of the sample along the loading
// axis (a compression test that fails through its body, by a shear band or axial splitting, has
// no end quarter dominating; one that crushes an end has), and, for a Brazilian disc, how close
// they lie to the loaded diameter (a central split keeps them within a narrow band). Pure
// functions over crack positions.
#include <array>
#include <cstddef>
#include <vector>

#include "breccia/core/vec3.hpp"

namespace breccia::analysis {

// Share of the cracks in each quarter of [lo, hi] along the axis (positions outside go to the
// nearest end quarter). All zero without cracks.
std::array<double, 4> quarter_shares(const std::vector<double>& axial_positions, double lo,
                                     double hi);

struct SplitPattern {
  std::size_t cracks = 0, early = 0;  // all, and the first `early_fraction` of them by time
  double early_tensile_share = 0.0;   // of the early cracks
  // Share within |offset| <= band x R of the loaded diameter (R the disc radius).
  double early_in_band = 0.0, all_in_band = 0.0;
  double early_mean_offset = 0.0;  // mean |offset| / R of the early cracks
  double band = 0.0;
};

// `offsets`: signed distance of each crack from the loaded diameter, in crack order (time);
// `tensile`: its mode. A uniform scatter over the disc puts (2 / pi) (b sqrt(1 - b^2) + asin b)
// of them in a band of half-width b R (31 % for b = 0.25); a central split puts most there.
SplitPattern split_pattern(const std::vector<double>& offsets, const std::vector<bool>& tensile,
                           double disc_radius, double early_fraction = 0.2, double band = 0.25);

// The plane (3D) or line (2D) that best fits the crack midpoints, by principal components: its
// normal is the direction of least spread. `angle_from_normal_plane_deg` is its angle to the plane
// normal to the load (0: a crack plane across the sample; 90: axial splitting; a Coulomb shear
// plane at 45 + phi / 2); `planarity` is 1 - (least spread / next spread), 0 for an isotropic
// cloud and 1 for cracks on one plane. Invalid with fewer than `min_cracks` cracks.
struct FailurePlane {
  bool valid = false;
  std::size_t cracks = 0;
  double angle_from_normal_plane_deg = 0.0;
  double planarity = 0.0;
  Vec3 normal;
};
FailurePlane failure_plane(const std::vector<Vec3>& positions, int axis, bool planar,
                           std::size_t min_cracks = 20);

}  // namespace breccia::analysis
