#pragma once
// Particle-size distributions for synthetic samples (docs/physics.md §7.1), reproducible from a
// seed: uniform in radius, lognormal truncated to [r_min, r_max], or discrete size classes given by
// radius and mass fraction (a grain-size curve).
#include <cstdint>
#include <string>
#include <vector>

namespace breccia {

struct RadiusDistribution {
  enum class Kind { Uniform, Lognormal, Classes };
  Kind kind = Kind::Uniform;
  double r_min = 0.0, r_max = 0.0;   // m; bounds for every kind (lognormal draws are truncated)
  double mean = 0.0, sd = 0.0;       // m; lognormal: mean and standard deviation of R itself
  std::vector<double> class_radius;  // m; Classes: one radius per class
  std::vector<double> class_mass_fraction;  // Classes: fraction of the solid mass in each class
  bool planar = false;                      // 2D: a class's particle "volume" is its disk area

  // Throws InputError naming `where` and the offending key when the settings are inconsistent.
  void validate(const std::string& where) const;
  // The k-th radius drawn with `seed` (a pure function of seed and k).
  double draw(std::uint64_t seed, std::uint64_t k) const;
  // Mean radius by number (what a large sample drawn from it has): exact for uniform and
  // classes, the mean of 4,096 draws with `seed` for the truncated lognormal.
  double number_mean(std::uint64_t seed) const;
  static Kind kind_from(const std::string& name, const std::string& where);
  static const char* name(Kind k);
};

// Radii drawn in order until their solid volume reaches `solid_volume` (docs/physics.md §7.1: the
// particle count for a target porosity). 2D counts disk areas times `thickness`.
std::vector<double> draw_radii_for_volume(const RadiusDistribution& dist, std::uint64_t seed,
                                          double solid_volume, bool planar, double thickness,
                                          std::size_t max_particles);

}  // namespace breccia
