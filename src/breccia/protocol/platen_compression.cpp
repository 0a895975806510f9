#include "breccia/protocol/platen_compression.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "breccia/core/error.hpp"
#include "breccia/core/format.hpp"

namespace breccia {

PlatenCompression::PlatenCompression(Simulation& sim, PlatenCompressionSettings s) : st_(s) {
  const ParticleStore& p = sim.particles();
  axis_ = p.planar() ? 1 : 2;
  const double inf = std::numeric_limits<double>::infinity();
  Vec3 lo{inf, inf, inf}, hi{-inf, -inf, -inf};
  for (const PosRad& q : p.pos_rad)
    for (int k = 0; k < 3; ++k) {
      lo[k] = std::min(lo[k], q.x[k] - q.r);
      hi[k] = std::max(hi[k], q.x[k] + q.r);
    }
  h0_ = hi[axis_] - lo[axis_];
  area_ = p.planar() ? (hi.x - lo.x) * p.thickness() : (hi.x - lo.x) * (hi.y - lo.y);
  Vec3 up{};
  up[axis_] = 1.0;
  Wall b = Wall::plane("platen_bottom", lo, up);
  Wall t = Wall::plane("platen_top", hi, -up);
  b.target_velocity = up * s.platen_speed;
  t.target_velocity = up * -s.platen_speed;
  bottom_ = sim.add_wall(b);
  top_ = sim.add_wall(t);
}

void PlatenCompression::start(Simulation& sim, double bar_wave_speed) {
  double ramp = st_.ramp_time;
  if (ramp <= 0.0) ramp = std::max(10.0 * h0_ / bar_wave_speed, 1000.0 * sim.time_step());
  for (std::size_t w : {bottom_, top_}) sim.walls()[w].ramp = {sim.time(), ramp};
}

AxialState PlatenCompression::measure(const Simulation& sim) const {
  const Wall& b = sim.walls()[bottom_];
  const Wall& t = sim.walls()[top_];
  AxialState s;
  const double h = t.point[axis_] - b.point[axis_];
  s.strain = (h0_ - h) / h0_;
  // Platen loads: the force the platen exerts on the sample, along its inward normal.
  s.force_bottom = dot(b.force, b.normal);
  s.force_top = dot(t.force, t.normal);
  s.stress = 0.5 * (s.force_bottom + s.force_top) / area_;
  return s;
}

bool PlatenCompression::finished(const AxialState& s, std::size_t broken_bonds) {
  peak_ = std::max(peak_, s.stress);
  if (s.strain >= st_.max_strain) {
    stop_reason_ = "reached the maximum strain " + num(st_.max_strain);
    return true;
  }
  if (broken_bonds > 0 && peak_ > 0.0 && s.stress < st_.stop_fraction * peak_) {
    stop_reason_ = "stress fell below " + num(st_.stop_fraction) + " of the peak";
    return true;
  }
  return false;
}

}  // namespace breccia
