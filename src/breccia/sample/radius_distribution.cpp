#include "breccia/sample/radius_distribution.hpp"

#include <cmath>
#include <numbers>
#include <numeric>

#include "breccia/core/error.hpp"
#include "breccia/core/format.hpp"
#include "breccia/core/rng.hpp"

namespace breccia {

namespace {
constexpr std::uint64_t kRadiusStream = 0x7261646975730000ull;  // "radius"
}

RadiusDistribution::Kind RadiusDistribution::kind_from(const std::string& name,
                                                       const std::string& where) {
  if (name == "uniform") return Kind::Uniform;
  if (name == "lognormal") return Kind::Lognormal;
  if (name == "classes") return Kind::Classes;
  throw InputError(where, "sample.distribution", "\"" + name + "\"",
                   "allowed: \"uniform\", \"lognormal\", \"classes\"");
}

const char* RadiusDistribution::name(Kind k) {
  switch (k) {
    case Kind::Uniform:
      return "uniform";
    case Kind::Lognormal:
      return "lognormal";
    case Kind::Classes:
      return "classes";
  }
  return "?";
}

void RadiusDistribution::validate(const std::string& where) const {
  if (kind != Kind::Classes) {  // classes carry their own radii
    if (!(r_min > 0.0) || !std::isfinite(r_min))
      throw InputError(where, "sample.radius_min", num(r_min), "must be a radius > 0 m");
    if (!(r_max >= r_min) || !std::isfinite(r_max))
      throw InputError(where, "sample.radius_max", num(r_max),
                       "must be >= sample.radius_min (" + num(r_min) + " m)");
  }
  if (kind == Kind::Lognormal) {
    if (!(mean > 0.0))
      throw InputError(where, "sample.radius_mean", num(mean), "must be > 0 m for a lognormal");
    if (!(sd >= 0.0)) throw InputError(where, "sample.radius_sd", num(sd), "must be >= 0 m");
    if (mean < r_min || mean > r_max)
      throw InputError(
          where, "sample.radius_mean", num(mean),
          "must lie within [radius_min, radius_max] = [" + num(r_min) + ", " + num(r_max) + "] m");
  }
  if (kind == Kind::Classes) {
    if (class_radius.empty() || class_radius.size() != class_mass_fraction.size())
      throw InputError(where, "sample.class_radii", std::to_string(class_radius.size()) + " radii",
                       "give one mass fraction per radius (sample.class_mass_fractions), at "
                       "least one class");
    double total = 0.0;
    for (std::size_t k = 0; k < class_radius.size(); ++k) {
      if (!(class_radius[k] > 0.0))
        throw InputError(where, "sample.class_radii", num(class_radius[k]),
                         "every radius must be > 0 m");
      if (!(class_mass_fraction[k] >= 0.0))
        throw InputError(where, "sample.class_mass_fractions", num(class_mass_fraction[k]),
                         "every fraction must be >= 0");
      total += class_mass_fraction[k];
    }
    if (std::abs(total - 1.0) > 1e-6)
      throw InputError(where, "sample.class_mass_fractions", num(total) + " in total",
                       "the fractions must add up to 1");
  }
}

double RadiusDistribution::draw(std::uint64_t seed, std::uint64_t k) const {
  switch (kind) {
    case Kind::Uniform:
      return r_min + uniform01(seed, kRadiusStream, k) * (r_max - r_min);
    case Kind::Lognormal: {
      // ln R ~ N(mu, s^2) with the moments of R itself (docs/physics.md §7.1), truncated by
      // redrawing.
      const double s2 = std::log1p(sd * sd / (mean * mean));
      const double mu = std::log(mean) - 0.5 * s2;
      for (std::uint64_t t = 0; t < 10000; ++t) {
        const double r =
            std::exp(mu + std::sqrt(s2) * standard_normal(seed, kRadiusStream + 1, k * 10000 + t));
        if (r >= r_min && r <= r_max) return r;
      }
      return mean;  // only when [r_min, r_max] holds almost no probability; moments are reported
    }
    case Kind::Classes: {
      // Number probability of a class = (mass fraction) / (volume of one of its particles).
      const double power = planar ? 2.0 : 3.0;
      double total = 0.0;
      for (std::size_t c = 0; c < class_radius.size(); ++c)
        total += class_mass_fraction[c] / std::pow(class_radius[c], power);
      double u = uniform01(seed, kRadiusStream + 2, k) * total;
      for (std::size_t c = 0; c < class_radius.size(); ++c) {
        u -= class_mass_fraction[c] / std::pow(class_radius[c], power);
        if (u <= 0.0) return class_radius[c];
      }
      return class_radius.back();
    }
  }
  return r_min;
}

double RadiusDistribution::number_mean(std::uint64_t seed) const {
  switch (kind) {
    case Kind::Uniform:
      return 0.5 * (r_min + r_max);
    case Kind::Classes: {
      const double power = planar ? 2.0 : 3.0;
      double count = 0.0, sum = 0.0;
      for (std::size_t c = 0; c < class_radius.size(); ++c) {
        const double n = class_mass_fraction[c] / std::pow(class_radius[c], power);
        count += n;
        sum += n * class_radius[c];
      }
      return sum / count;
    }
    case Kind::Lognormal:
      break;
  }
  constexpr std::uint64_t kDraws = 4096;
  double sum = 0.0;
  for (std::uint64_t k = 0; k < kDraws; ++k) sum += draw(seed, k);
  return sum / static_cast<double>(kDraws);
}

std::vector<double> draw_radii_for_volume(const RadiusDistribution& dist, std::uint64_t seed,
                                          double solid_volume, bool planar, double thickness,
                                          std::size_t max_particles) {
  std::vector<double> r;
  double v = 0.0;
  while (v < solid_volume) {
    if (r.size() >= max_particles)
      throw InputError("sample generation",
                       dist.kind == RadiusDistribution::Kind::Classes
                           ? "sample.class_radii"
                           : "sample.radius_min / sample.radius_max",
                       dist.kind == RadiusDistribution::Kind::Classes
                           ? std::string("(the classes given)")
                           : "grains of " + num(dist.r_min) + " to " + num(dist.r_max) + " m",
                       "the sample would need more than sample.max_particles = " +
                           std::to_string(max_particles) +
                           " grains of these radii; use larger grains, a smaller sample or raise "
                           "the limit");
    const double x = dist.draw(seed, r.size());
    r.push_back(x);
    v += planar ? std::numbers::pi * x * x * thickness : 4.0 / 3.0 * std::numbers::pi * x * x * x;
  }
  return r;
}

}  // namespace breccia
