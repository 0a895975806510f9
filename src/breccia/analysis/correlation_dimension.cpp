#include "breccia/analysis/correlation_dimension.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <unordered_map>

#include "breccia/analysis/stress_strain.hpp"

namespace breccia::analysis {

namespace {

// Number of distinct pairs closer than each radius (radii ascending), pairs beyond the largest
// radius ignored: all pairs for small sets, a cell list of cell size max(radii) otherwise.
std::vector<std::size_t> pair_counts(const std::vector<Vec3>& x, const std::vector<double>& radii) {
  const std::size_t nr = radii.size();
  std::vector<std::size_t> hist(nr + 1, 0);  // hist[k]: pairs with radii[k-1] <= d < radii[k]
  if (nr == 0) return {};
  const double rmax = radii.back();
  const auto add = [&](double d2) {
    if (d2 >= rmax * rmax) return;
    const double d = std::sqrt(d2);
    // first radius strictly greater than d
    const std::size_t k =
        static_cast<std::size_t>(std::upper_bound(radii.begin(), radii.end(), d) - radii.begin());
    ++hist[k];
  };
  const std::size_t n = x.size();
  if (n <= 5000) {
    for (std::size_t i = 0; i < n; ++i)
      for (std::size_t j = i + 1; j < n; ++j) add(norm2(x[j] - x[i]));
  } else {
    const double h = rmax;
    auto key = [](long long a, long long b, long long c) {
      return (a * 73856093LL) ^ (b * 19349663LL) ^ (c * 83492791LL);
    };
    struct Cell {
      long long a, b, c;
      std::vector<std::size_t> idx;
    };
    std::unordered_map<long long, std::vector<Cell>> grid;
    std::vector<std::array<long long, 3>> cell_of(n);
    for (std::size_t i = 0; i < n; ++i) {
      const std::array<long long, 3> c{static_cast<long long>(std::floor(x[i].x / h)),
                                       static_cast<long long>(std::floor(x[i].y / h)),
                                       static_cast<long long>(std::floor(x[i].z / h))};
      cell_of[i] = c;
      auto& bucket = grid[key(c[0], c[1], c[2])];
      auto it = std::find_if(bucket.begin(), bucket.end(), [&](const Cell& q) {
        return q.a == c[0] && q.b == c[1] && q.c == c[2];
      });
      if (it == bucket.end()) {
        bucket.push_back({c[0], c[1], c[2], {}});
        it = bucket.end() - 1;
      }
      it->idx.push_back(i);
    }
    for (std::size_t i = 0; i < n; ++i) {
      const auto& c = cell_of[i];
      for (long long da = -1; da <= 1; ++da)
        for (long long db = -1; db <= 1; ++db)
          for (long long dc = -1; dc <= 1; ++dc) {
            const auto g = grid.find(key(c[0] + da, c[1] + db, c[2] + dc));
            if (g == grid.end()) continue;
            for (const Cell& q : g->second) {
              if (q.a != c[0] + da || q.b != c[1] + db || q.c != c[2] + dc) continue;
              for (std::size_t j : q.idx)
                if (j > i) add(norm2(x[j] - x[i]));
            }
          }
    }
  }
  std::vector<std::size_t> out(nr, 0);
  std::size_t run = 0;
  for (std::size_t k = 0; k < nr; ++k) {
    run += hist[k];
    out[k] = run;
  }
  return out;
}

CorrelationDimension fit(const std::vector<double>& lr, const std::vector<double>& lc,
                         std::size_t points) {
  CorrelationDimension d;
  d.points = points;
  const LinearFit f = fit_line(lr, lc, 3);
  if (!f.valid) return d;
  d.d2 = f.slope;
  d.r2 = f.r2;
  d.radii_used = lr.size();
  d.r_min = std::pow(10.0, lr.front());
  d.r_max = std::pow(10.0, lr.back());
  double sxx = 0.0, mean = 0.0, ss = 0.0;
  for (double v : lr) mean += v;
  mean /= static_cast<double>(lr.size());
  for (std::size_t k = 0; k < lr.size(); ++k) {
    sxx += (lr[k] - mean) * (lr[k] - mean);
    const double e = lc[k] - (f.slope * lr[k] + f.intercept);
    ss += e * e;
  }
  d.standard_error =
      lr.size() > 2 ? std::sqrt(ss / static_cast<double>(lr.size() - 2) / sxx) : kNaN;
  return d;
}

}  // namespace

std::vector<double> correlation_integral(const std::vector<Vec3>& points,
                                         const std::vector<double>& radii) {
  const double n = static_cast<double>(points.size());
  const std::vector<std::size_t> c = pair_counts(points, radii);
  std::vector<double> out(radii.size(), kNaN);
  if (points.size() < 2) return out;
  for (std::size_t k = 0; k < radii.size(); ++k)
    out[k] = 2.0 * static_cast<double>(c[k]) / (n * (n - 1.0));
  return out;
}

CorrelationDimension correlation_dimension_fixed(const std::vector<Vec3>& points,
                                                 const std::vector<double>& radii) {
  const std::vector<double> c = correlation_integral(points, radii);
  std::vector<double> lr, lc;
  for (std::size_t k = 0; k < radii.size(); ++k)
    if (c[k] > 0.0) {
      lr.push_back(std::log10(radii[k]));
      lc.push_back(std::log10(c[k]));
    }
  return fit(lr, lc, points.size());
}

namespace {

// The smallest positive distance between two points: all pairs up to 5,000 points, else a scan
// of the points sorted along x (the nearest distance without the quadratic cost).
double smallest_distance(const std::vector<Vec3>& points) {
  double r_lo = std::numeric_limits<double>::infinity();
  const std::size_t n = points.size();
  if (n <= 5000) {
    for (std::size_t i = 0; i < n; ++i)
      for (std::size_t j = i + 1; j < n; ++j) {
        const double d = norm(points[j] - points[i]);
        if (d > 0.0) r_lo = std::min(r_lo, d);
      }
    return r_lo;
  }
  std::vector<Vec3> p = points;
  std::sort(p.begin(), p.end(), [](const Vec3& a, const Vec3& b) { return a.x < b.x; });
  for (std::size_t i = 0; i < n; ++i)
    for (std::size_t j = i + 1; j < n && p[j].x - p[i].x < r_lo; ++j) {
      const double d = norm(p[j] - p[i]);
      if (d > 0.0) r_lo = std::min(r_lo, d);
    }
  return r_lo;
}

// The correlation integral C(r) on the radius grid, and which radii may bound a scaling range
// (enough pairs, C <= 0.5).
struct CorrelationIntegral {
  std::vector<double> radii, c;
  std::vector<std::size_t> counts;
  std::vector<char> keep;
  std::size_t points = 0;
};

// The best straight run of log C over log r spanning at least `decades`: the smallest rms
// residual, the longer span among near-equal ones.
CorrelationDimension best_scaling_range(const CorrelationIntegral& ci, const D2Settings& s,
                                        double decades) {
  CorrelationDimension best;
  double best_rms = std::numeric_limits<double>::infinity(), best_span = 0.0;
  const auto& radii = ci.radii;
  for (std::size_t a = 0; a < radii.size(); ++a) {
    if (!ci.keep[a]) continue;
    for (std::size_t b = a; b < radii.size() && ci.keep[b]; ++b) {
      const std::size_t len = b - a + 1;
      const double span = std::log10(radii[b] / radii[a]);
      if (len < static_cast<std::size_t>(s.min_run) || span < decades - 1e-12) continue;
      std::vector<double> lr, lc;
      for (std::size_t k = a; k <= b; ++k) {
        lr.push_back(std::log10(radii[k]));
        lc.push_back(std::log10(ci.c[k]));
      }
      CorrelationDimension f = fit(lr, lc, ci.points);
      if (!f.valid()) continue;
      double ss = 0.0;
      const LinearFit line = fit_line(lr, lc, 3);
      for (std::size_t k = 0; k < lr.size(); ++k) {
        const double e = lc[k] - (line.slope * lr[k] + line.intercept);
        ss += e * e;
      }
      const double rms = std::sqrt(ss / static_cast<double>(lr.size()));
      if (rms < best_rms - 1e-4 || (std::abs(rms - best_rms) <= 1e-4 && span > best_span)) {
        best_rms = std::min(rms, best_rms);
        best_span = span;
        f.pairs_at_r_min = ci.counts[a];
        best = f;
      }
    }
  }
  return best;
}

}  // namespace

CorrelationDimension correlation_dimension(const std::vector<Vec3>& points, const D2Settings& s) {
  CorrelationDimension out;
  out.points = points.size();
  if (points.size() < s.min_points || points.size() < 2) {
    out.flags.push_back("too_few_points");
    return out;
  }
  // r_lo: the smallest positive nearest-neighbour distance; the radius grid starts there.
  const double r_lo = smallest_distance(points);
  if (!(r_lo < s.r_hi) || !(s.r_hi > 0.0)) {
    out.flags.push_back("no_scaling_range");
    return out;
  }
  CorrelationIntegral ci;
  ci.points = points.size();
  ci.radii.resize(static_cast<std::size_t>(s.radii));
  for (int k = 0; k < s.radii; ++k)
    ci.radii[static_cast<std::size_t>(k)] =
        r_lo * std::pow(s.r_hi / r_lo, static_cast<double>(k) / (s.radii - 1));
  ci.counts = pair_counts(points, ci.radii);
  const double n = static_cast<double>(points.size());
  ci.keep.resize(ci.radii.size());
  ci.c.resize(ci.radii.size());
  for (std::size_t k = 0; k < ci.radii.size(); ++k) {
    ci.c[k] = 2.0 * static_cast<double>(ci.counts[k]) / (n * (n - 1.0));
    ci.keep[k] = ci.counts[k] >= s.min_pairs && ci.c[k] <= 0.5;
  }
  CorrelationDimension best = best_scaling_range(ci, s, s.min_decades);
  if (!best.valid()) {
    best = best_scaling_range(ci, s, 0.5 * s.min_decades);
    if (best.valid()) best.flags.push_back("short_scaling_range");
  }
  if (!best.valid()) {
    out.flags.push_back("no_scaling_range");
    return out;
  }
  if (best.d2 < 0.0) best.flags.push_back("negative");
  if (best.d2 > s.dimension) best.flags.push_back("above_dimension");
  if (best.d2 > 2.0 * std::log10(n)) best.flags.push_back("eckmann_ruelle_limit");
  return best;
}

}  // namespace breccia::analysis
