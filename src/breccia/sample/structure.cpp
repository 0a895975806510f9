#include "breccia/sample/structure.hpp"

#include <algorithm>
#include <cmath>

#include "breccia/engine/neighbour_grid.hpp"

namespace breccia {

HomogeneityCheck check_homogeneity(const std::vector<ProfileSlice>& profile) {
  HomogeneityCheck h;
  const std::size_t n = profile.size();
  if (n < 3) return h;
  auto measure = [&](auto field, double& spread, double& end_diff, double& end_deficit) {
    double mean = 0.0;
    for (std::size_t k = 1; k + 1 < n; ++k) mean += field(profile[k]);
    mean /= static_cast<double>(n - 2);
    for (std::size_t k = 1; k + 1 < n; ++k)
      spread = std::max(spread, std::abs(field(profile[k]) - mean) / mean);
    const double a = field(profile.front()), b = field(profile.back());
    end_diff = std::abs(a - b) / (0.5 * (a + b));
    end_deficit = std::max(std::abs(a - mean), std::abs(b - mean)) / mean;
  };
  measure([](const ProfileSlice& s) { return s.bonds_per_grain; }, h.interior_bonds_spread,
          h.end_bonds_difference, h.end_bonds_deficit);
  measure([](const ProfileSlice& s) { return s.solid_fraction; }, h.interior_solid_spread,
          h.end_solid_difference, h.end_solid_deficit);
  return h;
}

namespace {

// Porosity (the overlaps' lenses taken off the solid) and the contact and bond coordinations.
void describe_packing(const std::vector<PosRad>& p, std::size_t bonds, const Region& region,
                      SampleStructure& s) {
  const bool planar = region.planar();
  const double t = region.thickness;
  PairList touching;
  build_neighbour_pairs(p, 0.0, planar, touching);
  double overlap = 0.0;
  std::size_t contacts = 0;
  for (std::size_t k = 0; k < touching.size(); ++k) {
    const PosRad& a = p[touching.first[k]];
    const PosRad& b = p[touching.second[k]];
    const double d = norm(b.x - a.x);
    if (d >= a.r + b.r) continue;
    overlap += lens_volume(a.r, b.r, d, planar, t);
    ++contacts;
  }
  double solid = 0.0;
  for (const PosRad& q : p)
    solid +=
        planar ? std::numbers::pi * q.r * q.r * t : 4.0 / 3.0 * std::numbers::pi * q.r * q.r * q.r;
  const double n = static_cast<double>(p.size());
  s.porosity = 1.0 - (solid - overlap) / region.volume();
  s.contact_coordination = 2.0 * static_cast<double>(contacts) / n;
  s.bond_coordination = 2.0 * static_cast<double>(bonds) / n;
}

// Floaters, grains with few or no bonds, and the bonds per grain away from the vessel walls.
void describe_bonding(const std::vector<PosRad>& p, const std::vector<std::uint32_t>& degree,
                      const Region& region, double gap_tolerance, int floater_contacts,
                      SampleStructure& s) {
  double r_max = 0.0;
  for (const PosRad& q : p) r_max = std::max(r_max, q.r);
  double interior_bonds = 0.0;
  std::size_t interior = 0;
  for (std::size_t i = 0; i < p.size(); ++i) {
    const int walls = region.walls_touched(p[i].x, p[i].r, gap_tolerance);
    s.floaters += static_cast<int>(degree[i]) + walls < floater_contacts ? 1 : 0;
    s.few_bonds += static_cast<int>(degree[i]) < floater_contacts ? 1 : 0;
    s.unbonded += degree[i] == 0 ? 1 : 0;
    if (region.wall_distance(p[i].x) > 2.0 * r_max) {
      interior_bonds += degree[i];
      ++interior;
    }
  }
  s.bonds_per_interior_particle =
      interior ? interior_bonds / static_cast<double>(interior) : s.bond_coordination;
}

// Profile along the profile axis: equal slices of the vessel's length along it, with their
// grains, bonds per grain and solid fraction.
void describe_profile(const std::vector<PosRad>& p, const std::vector<std::uint32_t>& degree,
                      const Region& region, int slices, SampleStructure& s) {
  const bool planar = region.planar();
  const double t = region.thickness;
  const int axis = region.profile_axis();
  s.profile_axis = axis;
  const double h = region.profile_length(), dz = h / slices, z0 = region.lower()[axis];
  s.profile.resize(static_cast<std::size_t>(slices));
  std::vector<double> degree_sum(s.profile.size(), 0.0), slab_solid(s.profile.size(), 0.0);
  for (int k = 0; k < slices; ++k) {
    s.profile[static_cast<std::size_t>(k)].lo = z0 + k * dz;
    s.profile[static_cast<std::size_t>(k)].hi = z0 + (k + 1) * dz;
  }
  for (std::size_t i = 0; i < p.size(); ++i) {
    const double c = p[i].x[axis] - z0;
    const int k = std::clamp(static_cast<int>(std::floor(c / dz)), 0, slices - 1);
    ++s.profile[static_cast<std::size_t>(k)].grains;
    degree_sum[static_cast<std::size_t>(k)] += degree[i];
    const int k0 = std::max(0, static_cast<int>(std::floor((c - p[i].r) / dz)));
    const int k1 = std::min(slices - 1, static_cast<int>(std::floor((c + p[i].r) / dz)));
    for (int m = k0; m <= k1; ++m)
      slab_solid[static_cast<std::size_t>(m)] +=
          solid_in_slab(c, p[i].r, m * dz, (m + 1) * dz, planar, t);
  }
  for (std::size_t k = 0; k < s.profile.size(); ++k) {
    ProfileSlice& sl = s.profile[k];
    sl.bonds_per_grain = sl.grains ? degree_sum[k] / static_cast<double>(sl.grains) : 0.0;
    sl.solid_fraction = slab_solid[k] / region.slab_volume(sl.lo, sl.hi);
  }
}

}  // namespace

SampleStructure describe_structure(
    const std::vector<PosRad>& p, const std::vector<std::pair<std::uint32_t, std::uint32_t>>& bonds,
    const Region& region, double gap_tolerance, int floater_contacts, int slices) {
  SampleStructure s;
  s.particles = p.size();
  s.bonds = bonds.size();
  s.floater_contacts = floater_contacts;
  if (p.empty()) return s;
  std::vector<std::uint32_t> degree(p.size(), 0);
  for (auto [i, j] : bonds) {
    ++degree[i];
    ++degree[j];
  }
  describe_packing(p, bonds.size(), region, s);
  describe_bonding(p, degree, region, gap_tolerance, floater_contacts, s);
  describe_profile(p, degree, region, slices, s);
  s.homogeneity = check_homogeneity(s.profile);
  return s;
}

}  // namespace breccia
