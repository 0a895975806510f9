#include "breccia/protocol/membrane.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>

#include "breccia/core/byte_text.hpp"
#include "breccia/core/error.hpp"
#include "breccia/core/ranks.hpp"
#include "breccia/engine/simulation.hpp"

namespace breccia {

namespace {

// How far a grain's surface reaches out on a side: towards -x on the left (0), +x on the right.
double reach(const PosRad& q, int side) {
  return side == 0 ? -(q.x.x - q.r) : q.x.x + q.r;
}

// Each cell's grain over every rank's choice (collective): `cells` holds this rank's choices
// (-1 for none), reach(cell, grain) how far the grain reaches out for that cell, which only
// its owner knows current. In rank order a later rank's grain wins only when it reaches strictly
// further: the first grain in index order that reaches furthest, as one process's search keeps.
template <class Reach>
void choose_furthest_over_ranks(std::vector<std::int64_t>& cells, Reach&& reach) {
  std::string mine;
  for (std::size_t c = 0; c < cells.size(); ++c) {
    bytes::put(mine, cells[c]);
    bytes::put(mine, cells[c] < 0 ? 0.0 : reach(c, static_cast<std::size_t>(cells[c])));
  }
  std::vector<double> best(cells.size(), 0.0);
  cells.assign(cells.size(), -1);
  for (const std::string& part : ranks::all_gather(mine)) {
    std::size_t at = 0;
    for (std::size_t c = 0; c < cells.size(); ++c) {
      const auto b = bytes::take<std::int64_t>(part, at);
      const auto r = bytes::take<double>(part, at);
      if (b >= 0 && (cells[c] < 0 || r > best[c])) {
        cells[c] = b;
        best[c] = r;
      }
    }
  }
}

}  // namespace

void Membrane2D::find_chains(const ParticleStore& p, double y_bottom, double y_top,
                             std::size_t from, std::size_t to) {
  double r_sum = 0.0;
  for (const PosRad& q : p.pos_rad) r_sum += q.r;
  const double bin = 2.0 * r_sum / static_cast<double>(std::max<std::size_t>(p.size(), 1));
  // Whole cells only, the last taking the remainder: a sliver of a cell under a platen may hold
  // the centre of a single small grain well inside the sample, which would become a chain grain.
  const double height = y_top - y_bottom;
  const auto bins = static_cast<std::size_t>(std::max(1.0, std::floor(height / bin)));
  for (int side = 0; side < 2; ++side) best_[side].assign(bins, -1);
  for (std::size_t i = from; i < to; ++i) {
    const PosRad& q = p.pos_rad[i];
    if (q.x.y < y_bottom || q.x.y > y_top) continue;
    const auto k = std::min(bins - 1, static_cast<std::size_t>((q.x.y - y_bottom) / bin));
    for (int side = 0; side < 2; ++side) {
      std::int64_t& b = best_[side][k];
      if (b < 0 || reach(q, side) > reach(p.pos_rad[static_cast<std::size_t>(b)], side))
        b = static_cast<std::int64_t>(i);
    }
  }
}

void Membrane2D::choose_over_ranks(const ParticleStore& p) {
  // Both sides in one collective: the left side's cells, then the right side's.
  std::vector<std::int64_t> cells(best_[0]);
  cells.insert(cells.end(), best_[1].begin(), best_[1].end());
  const std::size_t left = best_[0].size();
  choose_furthest_over_ranks(cells, [&](std::size_t cell, std::size_t i) {
    return reach(p.pos_rad[i], cell < left ? 0 : 1);
  });
  best_[0].assign(cells.begin(), cells.begin() + static_cast<std::ptrdiff_t>(left));
  best_[1].assign(cells.begin() + static_cast<std::ptrdiff_t>(left), cells.end());
}

void Membrane2D::make_chains() {
  for (int side = 0; side < 2; ++side) {
    chains_[side].clear();
    for (std::int64_t b : best_[side])
      if (b >= 0) chains_[side].push_back(static_cast<std::uint32_t>(b));
  }
  chain_grains_.assign(chains_[0].begin(), chains_[0].end());
  chain_grains_.insert(chain_grains_.end(), chains_[1].begin(), chains_[1].end());
  std::sort(chain_grains_.begin(), chain_grains_.end());
  chain_grains_.erase(std::unique(chain_grains_.begin(), chain_grains_.end()), chain_grains_.end());
}

void Membrane2D::find(const ParticleStore& p, double y_bottom, double y_top) {
  find_chains(p, y_bottom, y_top, 0, p.size());
  make_chains();
  measure_lengths(p, y_bottom, y_top);
}

void Membrane2D::measure_lengths(const ParticleStore& p, double y_bottom, double y_top) {
  for (int side = 0; side < 2; ++side) {
    const auto& chain = chains_[side];
    auto& len = lengths_[side];
    len.assign(chain.size(), 0.0);
    if (chain.empty()) continue;
    len.front() += p.pos_rad[chain.front()].x.y - y_bottom;
    len.back() += y_top - p.pos_rad[chain.back()].x.y;
    for (std::size_t k = 0; k + 1 < chain.size(); ++k) {
      const Vec3 d = p.pos_rad[chain[k + 1]].x - p.pos_rad[chain[k]].x;
      const double half = 0.5 * std::hypot(d.x, d.y);
      len[k] += half;
      len[k + 1] += half;
    }
  }
}

void Membrane2D::apply(Simulation& sim, double sigma3, double y_bottom, double y_top) {
  const ParticleStore& p = sim.particles();
  if (sim.split()) {
    const IndexRange own = sim.owned_particles();
    find_chains(p, y_bottom, y_top, own.begin, own.end);
    choose_over_ranks(p);
    make_chains();
    sim.gather_grains({.all = false, .some = chain_grains_});
    measure_lengths(p, y_bottom, y_top);
  } else {
    find(p, y_bottom, y_top);
  }
  std::vector<Vec3>& load = sim.external_force();
  const double pressure_per_length = sigma3 * p.thickness();
  double inward = 0.0;
  for (int side = 0; side < 2; ++side) {
    const auto& chain = chains_[side];
    if (chain.empty()) continue;
    // A segment from a to b (b the higher end) pushes inwards with sigma_3 t times the segment
    // turned clockwise (left side, inward +x) or anticlockwise (right side, inward -x).
    const double turn = side == 0 ? 1.0 : -1.0;
    auto push = [&](const Vec3& a, const Vec3& b) {
      const Vec3 d = b - a;
      const Vec3 f{turn * d.y * pressure_per_length, -turn * d.x * pressure_per_length, 0.0};
      inward += turn * f.x;
      return f;
    };
    const Vec3 first = p.pos_rad[chain.front()].x, last = p.pos_rad[chain.back()].x;
    load[chain.front()] += push({first.x, y_bottom, 0.0}, first);
    load[chain.back()] += push(last, {last.x, y_top, 0.0});
    for (std::size_t k = 0; k + 1 < chain.size(); ++k) {
      const Vec3 f = push(p.pos_rad[chain[k]].x, p.pos_rad[chain[k + 1]].x);
      load[chain[k]] += f * 0.5;
      load[chain[k + 1]] += f * 0.5;
    }
  }
  stress_ = inward / (2.0 * (y_top - y_bottom) * p.thickness());
}

double Membrane2D::width(const ParticleStore& p) const {
  double surface[2] = {0.0, 0.0};
  for (int side = 0; side < 2; ++side) {
    double sum = 0.0, weight = 0.0;
    for (std::size_t k = 0; k < chains_[side].size(); ++k) {
      const PosRad& q = p.pos_rad[chains_[side][k]];
      sum += lengths_[side][k] * (side == 0 ? q.x.x - q.r : q.x.x + q.r);
      weight += lengths_[side][k];
    }
    surface[side] = weight > 0.0 ? sum / weight : 0.0;
  }
  return surface[1] - surface[0];
}

}  // namespace breccia

namespace breccia {

double MembraneCylinder::reach(const PosRad& q) const {
  return std::hypot(q.x.x - centre_.x, q.x.y - centre_.y) + q.r;
}

void MembraneCylinder::find_nodes(const ParticleStore& p, std::size_t from, std::size_t to,
                                  bool over_ranks) {
  double r_sum = 0.0;
  for (const PosRad& q : p.pos_rad) r_sum += q.r;
  const double d = 2.0 * r_sum / static_cast<double>(std::max<std::size_t>(p.size(), 1));
  double outer = 0.0;
  for (std::size_t i = from; i < to; ++i) {
    const PosRad& q = p.pos_rad[i];
    if (q.x.z >= z_bottom_ && q.x.z <= z_top_) outer = std::max(outer, reach(q));
  }
  if (over_ranks) {
    std::string mine;
    bytes::put(mine, outer);
    for (const std::string& part : ranks::all_gather(mine)) {
      std::size_t at = 0;
      outer = std::max(outer, bytes::take<double>(part, at));
    }
  }
  // Cells about one mean diameter of arc at the outer radius, and one tall; at least six around.
  columns_ = std::max<std::size_t>(
      6, static_cast<std::size_t>(std::llround(2.0 * std::numbers::pi * outer / d)));
  rows_ = static_cast<std::size_t>(std::max(1.0, std::ceil((z_top_ - z_bottom_) / d)));
  const double dz = (z_top_ - z_bottom_) / static_cast<double>(rows_);
  node_.assign(columns_ * rows_, -1);
  for (std::size_t i = from; i < to; ++i) {
    const PosRad& q = p.pos_rad[i];
    if (q.x.z < z_bottom_ || q.x.z > z_top_) continue;
    const double theta = std::atan2(q.x.y - centre_.y, q.x.x - centre_.x);
    const auto col =
        std::min(columns_ - 1,
                 static_cast<std::size_t>((theta + std::numbers::pi) / (2.0 * std::numbers::pi) *
                                          static_cast<double>(columns_)));
    const auto row = std::min(rows_ - 1, static_cast<std::size_t>((q.x.z - z_bottom_) / dz));
    std::int64_t& b = node_[col + columns_ * row];
    if (b < 0 || reach(q) > reach(p.pos_rad[static_cast<std::size_t>(b)]))
      b = static_cast<std::int64_t>(i);
  }
}

void MembraneCylinder::choose_over_ranks(const ParticleStore& p) {
  choose_furthest_over_ranks(node_,
                             [&](std::size_t, std::size_t i) { return reach(p.pos_rad[i]); });
}

void MembraneCylinder::fill_and_list() {
  for (std::size_t row = 0; row < rows_; ++row) {
    std::int64_t* cells = node_.data() + columns_ * row;
    std::size_t filled = 0;
    for (std::size_t k = 0; k < columns_; ++k) filled += cells[k] >= 0 ? 1 : 0;
    if (filled == 0) throw InternalError("the membrane found no grain at one level of the sample");
    // Going down the columns, an empty cell takes the choice of the next cell round the axis.
    for (std::size_t k = columns_; k-- > 0;)
      if (cells[k] < 0) {
        std::size_t n = (k + 1) % columns_;
        while (cells[n] < 0) n = (n + 1) % columns_;
        cells[k] = cells[n];
      }
  }
  grains_.clear();
  for (const std::int64_t b : node_) grains_.push_back(static_cast<std::uint32_t>(b));
  std::sort(grains_.begin(), grains_.end());
  grains_.erase(std::unique(grains_.begin(), grains_.end()), grains_.end());
}

void MembraneCylinder::find(const ParticleStore& p, const Vec3& centre, double z_bottom,
                            double z_top) {
  centre_ = centre;
  z_bottom_ = z_bottom;
  z_top_ = z_top;
  find_nodes(p, 0, p.size(), false);
  fill_and_list();
}

std::uint32_t MembraneCylinder::grain_at(std::size_t k, std::size_t j) const {
  const std::size_t row = j == 0 ? 0 : std::min(j - 1, rows_ - 1);
  return static_cast<std::uint32_t>(node_[k + columns_ * row]);
}

Vec3 MembraneCylinder::node_at(const ParticleStore& p, std::size_t k, std::size_t j) const {
  Vec3 x = p.pos_rad[grain_at(k, j)].x;
  if (j == 0) x.z = z_bottom_;
  if (j == rows_ + 1) x.z = z_top_;
  return x;
}

MembraneCylinder::FaceSums MembraneCylinder::load_faces(const ParticleStore& p, double sigma3,
                                                        std::vector<Vec3>* load) const {
  FaceSums s;
  for (std::size_t k = 0; k < columns_; ++k) {
    const std::size_t next = (k + 1) % columns_;
    for (std::size_t j = 0; j <= rows_; ++j) {
      const std::uint32_t g[4] = {grain_at(k, j), grain_at(next, j), grain_at(next, j + 1),
                                  grain_at(k, j + 1)};
      const Vec3 a = node_at(p, k, j), b = node_at(p, next, j), c = node_at(p, next, j + 1),
                 d = node_at(p, k, j + 1);
      // Around the axis anticlockwise, then up: the area vector points outward.
      const Vec3 area = cross(c - a, d - b) * 0.5;
      const Vec3 mid = (a + b + c + d) * 0.25;
      const double rho = std::hypot(mid.x - centre_.x, mid.y - centre_.y);
      const Vec3 out{(mid.x - centre_.x) / rho, (mid.y - centre_.y) / rho, 0.0};
      const double radial = dot(area, out);
      s.radial_area += radial;
      s.inward += sigma3 * radial;
      double r = 0.0;
      for (std::uint32_t i : g) r += 0.25 * reach(p.pos_rad[i]);
      s.reach += r * radial;
      if (load)
        for (std::uint32_t i : g) (*load)[i] += area * (-0.25 * sigma3);
    }
  }
  return s;
}

void MembraneCylinder::apply(Simulation& sim, double sigma3, const Vec3& centre, double z_bottom,
                             double z_top) {
  const ParticleStore& p = sim.particles();
  centre_ = centre;
  z_bottom_ = z_bottom;
  z_top_ = z_top;
  if (sim.split()) {
    const IndexRange own = sim.owned_particles();
    find_nodes(p, own.begin, own.end, true);
    choose_over_ranks(p);
    fill_and_list();
    sim.gather_grains({.all = false, .some = grains_});
  } else {
    find_nodes(p, 0, p.size(), false);
    fill_and_list();
  }
  const FaceSums s = load_faces(p, sigma3, &sim.external_force());
  stress_ = s.radial_area > 0.0 ? s.inward / s.radial_area : 0.0;
}

double MembraneCylinder::diameter(const ParticleStore& p) const {
  const FaceSums s = load_faces(p, 0.0, nullptr);
  return s.radial_area > 0.0 ? 2.0 * s.reach / s.radial_area : 0.0;
}

}  // namespace breccia
