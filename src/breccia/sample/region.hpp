#pragma once
// The vessel a sample is packed in: a prism or a cylinder (3D, axis z), a rectangle or a disk (2D,
// in the x-y plane). Lowest corner (prism, rectangle) or axis foot (cylinder) or centre (disk) at
// the origin. The loading axis is the last one: z in 3D, y in 2D.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numbers>
#include <vector>

#include "breccia/core/rng.hpp"
#include "breccia/core/vec3.hpp"
#include "breccia/sample/tangent_fit.hpp"

namespace breccia {

enum class SampleShape { Prism, Cylinder, Rectangle, Disk };

struct Region {
  SampleShape shape = SampleShape::Prism;
  double lx = 0, ly = 0, lz = 0;  // prism: extents; rectangle: lx, ly (lz = 0); cylinder: lz
  double radius = 0;              // cylinder, disk
  double thickness = 1.0;         // rectangle: disk thickness

  bool planar() const noexcept {
    return shape == SampleShape::Rectangle || shape == SampleShape::Disk;
  }
  bool round() const noexcept {
    return shape == SampleShape::Cylinder || shape == SampleShape::Disk;
  }
  int dimension() const noexcept { return planar() ? 2 : 3; }
  int axis() const noexcept { return planar() ? 1 : 2; }
  // Length along the profile axis.
  double height() const noexcept {
    return shape == SampleShape::Disk ? 2 * radius : (planar() ? ly : lz);
  }
  // Area normal to the loading axis (2D: width x thickness).
  double cross_section() const noexcept {
    switch (shape) {
      case SampleShape::Prism:
        return lx * ly;
      case SampleShape::Cylinder:
        return std::numbers::pi * radius * radius;
      case SampleShape::Rectangle:
        return lx * thickness;
      case SampleShape::Disk:
        return 2 * radius * thickness;  // at its widest; see slab_volume
    }
    return 0.0;
  }
  double volume() const noexcept {
    return shape == SampleShape::Disk ? std::numbers::pi * radius * radius * thickness
                                      : cross_section() * height();
  }
  // The axis the homogeneity profile runs along: the loading axis, unless a box vessel is longer
  // across it (a slab: eighths of its thickness would be thinner than its grains), then its
  // longest side (x before y on a tie).
  int profile_axis() const noexcept {
    if (round()) return axis();
    const double along = planar() ? ly : lz;
    if (lx > along && (planar() || lx >= ly)) return 0;
    if (!planar() && ly > along) return 1;
    return axis();
  }
  // The vessel's length along the profile axis.
  double profile_length() const noexcept {
    return round() ? height() : upper()[profile_axis()] - lower()[profile_axis()];
  }
  // Volume of the vessel between a <= coordinate along the profile axis <= b.
  double slab_volume(double a, double b) const noexcept {
    if (shape != SampleShape::Disk) return volume() / profile_length() * (b - a);
    auto f = [&](double u) {
      const double s = std::clamp(u / radius, -1.0, 1.0);
      return u * std::sqrt(std::max(0.0, radius * radius - u * u)) + radius * radius * std::asin(s);
    };
    return (f(b) - f(a)) * thickness;
  }
  // Smallest extent across the sample (for the resolution check).
  double smallest_extent() const noexcept {
    switch (shape) {
      case SampleShape::Prism:
        return std::min({lx, ly, lz});
      case SampleShape::Cylinder:
        return std::min(2 * radius, lz);
      case SampleShape::Rectangle:
        return std::min(lx, ly);
      case SampleShape::Disk:
        return 2 * radius;
    }
    return 0.0;
  }

  // A random centre for a particle of radius r fully inside, from the counter-based generator.
  // `axial_lo`, `axial_hi` (fractions of the height) restrict the axial coordinate to a stratum.
  Vec3 draw(double r, std::uint64_t seed, std::uint64_t stream, std::uint64_t& counter,
            double axial_lo = 0.0, double axial_hi = 1.0) const {
    auto u = [&] { return uniform01(seed, stream, counter++); };
    auto axial = [&](double length) {
      const double lo = std::max(r, axial_lo * length),
                   hi = std::min(length - r, axial_hi * length);
      return hi > lo ? lo + u() * (hi - lo) : r + u() * (length - 2 * r);
    };
    switch (shape) {
      case SampleShape::Prism: {
        const double x = r + u() * (lx - 2 * r), y = r + u() * (ly - 2 * r);
        return {x, y, axial(lz)};
      }
      case SampleShape::Cylinder: {
        const double rho = (radius - r) * std::sqrt(u());
        const double phi = 2.0 * std::numbers::pi * u();
        return {rho * std::cos(phi), rho * std::sin(phi), axial(lz)};
      }
      case SampleShape::Rectangle: {
        const double x = r + u() * (lx - 2 * r);
        return {x, axial(ly), 0.0};
      }
      case SampleShape::Disk: {
        // Uniform in the disk of radius R - r; the axial stratum is a band of y.
        for (int k = 0; k < 1000; ++k) {
          const double x = (radius - r) * (2 * u() - 1);
          const double y = -radius + axial(2 * radius);
          if (x * x + y * y <= (radius - r) * (radius - r)) return {x, y, 0.0};
        }
        return {};
      }
    }
    return {};
  }
  // Distance from a point to the nearest vessel wall (negative outside).
  double wall_distance(const Vec3& x) const noexcept {
    switch (shape) {
      case SampleShape::Prism:
        return std::min({x.x, lx - x.x, x.y, ly - x.y, x.z, lz - x.z});
      case SampleShape::Cylinder:
        return std::min({radius - std::hypot(x.x, x.y), x.z, lz - x.z});
      case SampleShape::Rectangle:
        return std::min({x.x, lx - x.x, x.y, ly - x.y});
      case SampleShape::Disk:
        return radius - std::hypot(x.x, x.y);
    }
    return 0.0;
  }
  // Number of vessel walls a particle touches (surface gap at most `tol`).
  int walls_touched(const Vec3& x, double r, double tol) const noexcept {
    int n = 0;
    auto touch = [&](double d) { n += (d - r <= tol) ? 1 : 0; };
    switch (shape) {
      case SampleShape::Prism:
        for (double d : {x.x, lx - x.x, x.y, ly - x.y, x.z, lz - x.z}) touch(d);
        break;
      case SampleShape::Cylinder:
        for (double d : {radius - std::hypot(x.x, x.y), x.z, lz - x.z}) touch(d);
        break;
      case SampleShape::Rectangle:
        for (double d : {x.x, lx - x.x, x.y, ly - x.y}) touch(d);
        break;
      case SampleShape::Disk:
        touch(radius - std::hypot(x.x, x.y));
        break;
    }
    return n;
  }
  // The vessel walls as planes for the tangent fits (§7.4); the cylinder's side as its tangent
  // plane at the point nearest to x (exact once the fit is iterated with its own centre).
  std::vector<Surface> wall_surfaces(const Vec3& x) const {
    auto plane = [](Vec3 p, Vec3 n) { return Surface{true, p, n, 0.0}; };
    switch (shape) {
      case SampleShape::Prism:
        return {plane({0, 0, 0}, {1, 0, 0}), plane({lx, 0, 0}, {-1, 0, 0}),
                plane({0, 0, 0}, {0, 1, 0}), plane({0, ly, 0}, {0, -1, 0}),
                plane({0, 0, 0}, {0, 0, 1}), plane({0, 0, lz}, {0, 0, -1})};
      case SampleShape::Cylinder: {
        const double rho = std::hypot(x.x, x.y);
        const Vec3 out = rho > 0.0 ? Vec3{x.x / rho, x.y / rho, 0.0} : Vec3{1, 0, 0};
        return {plane(out * radius, -out), plane({0, 0, 0}, {0, 0, 1}),
                plane({0, 0, lz}, {0, 0, -1})};
      }
      case SampleShape::Rectangle:
        return {plane({0, 0, 0}, {1, 0, 0}), plane({lx, 0, 0}, {-1, 0, 0}),
                plane({0, 0, 0}, {0, 1, 0}), plane({0, ly, 0}, {0, -1, 0})};
      case SampleShape::Disk: {
        const double rho = std::hypot(x.x, x.y);
        const Vec3 out = rho > 0.0 ? Vec3{x.x / rho, x.y / rho, 0.0} : Vec3{1, 0, 0};
        return {plane(out * radius, -out)};
      }
    }
    return {};
  }
  Vec3 lower() const noexcept { return round() ? Vec3{-radius, -radius, 0} : Vec3{}; }
  Vec3 upper() const noexcept {
    if (shape == SampleShape::Cylinder) return {radius, radius, lz};
    if (shape == SampleShape::Disk) return {radius, radius, 0};
    return {lx, ly, planar() ? 0.0 : lz};
  }
};

// Solid volume of a sphere (3D) or disk of thickness t (2D) of radius r centred at axial
// coordinate c that lies between the planes (lines) at a and b.
inline double solid_in_slab(double c, double r, double a, double b, bool planar,
                            double thickness) noexcept {
  const double u1 = std::max(a - c, -r), u2 = std::min(b - c, r);
  if (u1 >= u2) return 0.0;
  if (!planar) return std::numbers::pi * (r * r * (u2 - u1) - (u2 * u2 * u2 - u1 * u1 * u1) / 3.0);
  auto f = [r](double u) {
    const double s = std::clamp(u / r, -1.0, 1.0);
    return u * std::sqrt(std::max(0.0, r * r - u * u)) + r * r * std::asin(s);
  };
  return (f(u2) - f(u1)) * thickness;
}

// Lens volume (3D) or area times thickness (2D) shared by two overlapping particles (§7.7).
inline double lens_volume(double r1, double r2, double d, bool planar, double t) noexcept {
  if (d >= r1 + r2 || d <= 0.0) return 0.0;
  if (!planar) {
    const double h = r1 + r2 - d;
    return std::numbers::pi * h * h * (d * d + 2 * d * (r1 + r2) - 3 * (r1 - r2) * (r1 - r2)) /
           (12.0 * d);
  }
  const double a =
      r1 * r1 * std::acos(std::clamp((d * d + r1 * r1 - r2 * r2) / (2 * d * r1), -1.0, 1.0)) +
      r2 * r2 * std::acos(std::clamp((d * d + r2 * r2 - r1 * r1) / (2 * d * r2), -1.0, 1.0)) -
      0.5 *
          std::sqrt(std::max(0.0, (-d + r1 + r2) * (d + r1 - r2) * (d - r1 + r2) * (d + r1 + r2)));
  return a * t;
}

}  // namespace breccia
