#include "breccia/sample/tangent_fit.hpp"

#include <algorithm>
#include <cmath>

namespace breccia {

namespace {

constexpr double kMaxCondition = 1e8;

// One tangency condition made linear: alpha . x + beta r = gamma (relative to the reference
// sphere s for spheres; exact for planes).
struct Row {
  Vec3 alpha;
  double beta = 0.0, gamma = 0.0;
};

Row linear_row(const Surface& k, const Surface& s) {
  if (k.plane) return {k.normal, -1.0, dot(k.point, k.normal)};  // (x - p) . m = r
  return {2.0 * (k.point - s.point), 2.0 * (k.radius - s.radius),
          norm2(k.point) - norm2(s.point) - k.radius * k.radius + s.radius * s.radius};
}

int reference_sphere(const std::vector<Surface>& surfaces) {
  for (std::size_t i = 0; i < surfaces.size(); ++i)
    if (!surfaces[i].plane) return static_cast<int>(i);
  return -1;
}

// Real roots of a t^2 + b t + c = 0 (a may vanish).
std::vector<double> quadratic_roots(double a, double b, double c) {
  const double scale = std::max({std::abs(a), std::abs(b), std::abs(c)});
  if (scale == 0.0) return {};
  if (std::abs(a) <= 1e-14 * scale) {
    if (std::abs(b) <= 1e-300) return {};
    return {-c / b};
  }
  const double disc = b * b - 4 * a * c;
  if (disc < 0.0) return {};
  const double q = -0.5 * (b + std::copysign(std::sqrt(disc), b));
  std::vector<double> r{q / a};
  if (q != 0.0) r.push_back(c / q);
  return r;
}

}  // namespace

namespace {
// x = a + b r from the D linear rows A x = gamma - beta r, by the explicit inverse (adjugate)
// with the Frobenius condition number |A| |A^-1| as the singularity test.
bool solve_centre_line(const std::vector<Row>& rows, bool planar, Vec3& a, Vec3& b) {
  const Vec3 r0 = rows[0].alpha, r1 = rows[1].alpha;
  double inv[3][3] = {};
  double norm_a = 0.0, norm_inv = 0.0;
  if (planar) {
    const double det = r0.x * r1.y - r0.y * r1.x;
    if (det == 0.0) return false;
    const double m[2][2] = {{r1.y / det, -r0.y / det}, {-r1.x / det, r0.x / det}};
    for (int i = 0; i < 2; ++i)
      for (int j = 0; j < 2; ++j) inv[i][j] = m[i][j];
    norm_a = r0.x * r0.x + r0.y * r0.y + r1.x * r1.x + r1.y * r1.y;
  } else {
    const Vec3 r2 = rows[2].alpha;
    // Rows of A are r0, r1, r2: A^-1 has columns (r1 x r2, r2 x r0, r0 x r1) / det.
    const Vec3 c0 = cross(r1, r2), c1 = cross(r2, r0), c2 = cross(r0, r1);
    const double det = dot(r0, c0);
    if (det == 0.0) return false;
    for (int i = 0; i < 3; ++i) {
      inv[i][0] = c0[i] / det;
      inv[i][1] = c1[i] / det;
      inv[i][2] = c2[i] / det;
    }
    norm_a = norm2(r0) + norm2(r1) + norm2(r2);
  }
  const int dim = planar ? 2 : 3;
  for (int i = 0; i < dim; ++i)
    for (int j = 0; j < dim; ++j) norm_inv += inv[i][j] * inv[i][j];
  if (!(std::sqrt(norm_a * norm_inv) <= kMaxCondition)) return false;
  a = {};
  b = {};
  for (int i = 0; i < dim; ++i)
    for (int j = 0; j < dim; ++j) {
      a[i] += inv[i][j] * rows[static_cast<std::size_t>(j)].gamma;
      b[i] -= inv[i][j] * rows[static_cast<std::size_t>(j)].beta;
    }
  return true;
}
}  // namespace

std::vector<FittedSphere> fit_free_radius(const std::vector<Surface>& surfaces, bool planar) {
  const int dim = planar ? 2 : 3;
  if (static_cast<int>(surfaces.size()) != dim + 1) return {};
  const int s = reference_sphere(surfaces);
  if (s < 0) return {};
  const Surface& ref = surfaces[static_cast<std::size_t>(s)];
  std::vector<Row> rows;
  for (int k = 0; k <= dim; ++k)
    if (k != s) rows.push_back(linear_row(surfaces[static_cast<std::size_t>(k)], ref));
  Vec3 a, b;
  if (!solve_centre_line(rows, planar, a, b)) return {};
  // |x - c_s|^2 = (r + R_s)^2 with x = a + b r.
  const Vec3 d = a - ref.point;
  std::vector<FittedSphere> out;
  for (double r : quadratic_roots(norm2(b) - 1.0, 2.0 * (dot(b, d) - ref.radius),
                                  norm2(d) - ref.radius * ref.radius))
    if (r > 0.0 && std::isfinite(r)) out.push_back({a + b * r, r});
  std::sort(out.begin(), out.end(),
            [](const FittedSphere& p, const FittedSphere& q) { return p.radius < q.radius; });
  return out;
}

std::vector<Vec3> fit_fixed_radius(const std::vector<Surface>& surfaces, double radius, bool planar,
                                   const Vec3& near) {
  const int dim = planar ? 2 : 3;
  if (static_cast<int>(surfaces.size()) != dim) return {};
  const int s = reference_sphere(surfaces);
  if (s < 0) return {};
  const Surface& ref = surfaces[static_cast<std::size_t>(s)];
  // The other D - 1 conditions are linear in x: alpha . x = gamma - beta r.
  std::vector<Row> rows;
  for (int k = 0; k < dim; ++k)
    if (k != s) rows.push_back(linear_row(surfaces[static_cast<std::size_t>(k)], ref));
  // Solutions lie on x = x0 + t dir: a line (3D: two planes meet) or, in 2D, one line.
  Vec3 x0, dir;
  if (planar) {
    const Row& r = rows[0];
    const double n2 = r.alpha.x * r.alpha.x + r.alpha.y * r.alpha.y;
    if (!(n2 > 0.0)) return {};
    x0 = r.alpha * ((r.gamma - r.beta * radius) / n2);
    x0.z = 0.0;
    dir = unit(Vec3{-r.alpha.y, r.alpha.x, 0.0});
  } else {
    const Vec3 n1 = rows[0].alpha, n2 = rows[1].alpha;
    const double g1 = rows[0].gamma - rows[0].beta * radius;
    const double g2 = rows[1].gamma - rows[1].beta * radius;
    dir = cross(n1, n2);
    const double len2 = norm2(dir);
    if (!(len2 > 1e-16 * norm2(n1) * norm2(n2))) return {};
    // The point of both planes closest to the origin.
    x0 = (cross(n2, dir) * g1 + cross(dir, n1) * g2) / len2;
    dir = dir / std::sqrt(len2);
  }
  const Vec3 d = x0 - ref.point;
  const double reach = radius + ref.radius;
  std::vector<Vec3> out;
  for (double t : quadratic_roots(1.0, 2.0 * dot(dir, d), norm2(d) - reach * reach))
    if (std::isfinite(t)) out.push_back(x0 + dir * t);
  std::sort(out.begin(), out.end(),
            [&](const Vec3& p, const Vec3& q) { return norm2(p - near) < norm2(q - near); });
  return out;
}

}  // namespace breccia
