// The integrator (docs/physics.md §1.3-§1.4, §2.1): each particle's pair and wall loads (summed by
// the pair and wall passes) with its cross slots added in a fixed order, external loads and
// gravity, local damping (lowered near fresh cracks by dynamic damping), then the leapfrog kick and
// drift and the rotation update.
#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>

#include "breccia/core/error.hpp"
#include "breccia/core/format.hpp"
#include "breccia/core/parallel.hpp"
#include "breccia/engine/pair_lists.hpp"
#include "breccia/engine/simulation.hpp"

namespace breccia {

using namespace engine_detail;

namespace {

// A particle's new velocities and the step's interval of time, as a stage sees them.
struct Kick {
  Vec3 v_old, w_old;  // v^{n-1/2}, w^{n-1/2}
  Vec3 v_new, w_new;  // v^{n+1/2}, w^{n+1/2}
};

// A free particle: Cundall local damping, its sign tested with the predicted full-step velocity
// (§2.1), then the leapfrog kick.
inline void kick_free(Vec3 f, Vec3 t, double m, double inertia, double dt, double alpha,
                      bool sample, Kick& k, IntegrateBlock& acc) {
  // Two divisions, not four: 0.5 (dt / m) is (0.5 dt) / m to the bit (halving is exact).
  const double dt_m = dt / m, dt_i = dt / inertia;
  if (alpha > 0.0) {
    const Vec3 vp = k.v_old + f * (0.5 * dt_m);
    const Vec3 wp = k.w_old + t * (0.5 * dt_i);
    Vec3 fd, td;
    for (int c = 0; c < 3; ++c) {
      fd[c] = -alpha * std::abs(f[c]) * ((vp[c] > 0.0) - (vp[c] < 0.0));
      td[c] = -alpha * std::abs(t[c]) * ((wp[c] > 0.0) - (wp[c] < 0.0));
    }
    f += fd;
    t += td;
    k.v_new = k.v_old + f * dt_m;
    k.w_new = k.w_old + t * dt_i;
    // The loss is booked as minus the work of the damping force with the same trapezoidal rule
    // as every other term, (1/2) F_d . (v^{n-1/2} + v^{n+1/2}) dt, so the ledger closes; it
    // equals docs/physics.md's alpha dt sum |F||v~| to O(dt). The half that pairs with
    // v^{n+1/2} belongs to the next interval and is removed from a sample.
    acc.local_damping -= 0.5 * (dot(fd, k.v_old + k.v_new) + dot(td, k.w_old + k.w_new)) * dt;
    if (sample) acc.damping_boundary -= 0.5 * (dot(fd, k.v_new) + dot(td, k.w_new)) * dt;
  } else {
    k.v_new = k.v_old + f * dt_m;
    k.w_new = k.w_old + t * dt_i;
  }
}

// A fixed or driven particle: the driver supplies whatever force keeps the prescribed motion;
// its work is booked with the trapezoidal rule like the walls'.
inline void kick_driven(bool fixed, const Vec3& drive_v, const Vec3& drive_w, bool planar,
                        const Vec3& f, const Vec3& t, double m, double inertia, double dt,
                        Vec3& fd_prev, Vec3& td_prev, Kick& k, IntegrateBlock& acc) {
  k.v_new = fixed ? Vec3{} : drive_v;
  k.w_new = fixed ? Vec3{} : drive_w;
  if (planar) {
    k.v_new.z = 0.0;
    k.w_new.x = 0.0;
    k.w_new.y = 0.0;
  }
  const Vec3 fd = (k.v_new - k.v_old) * (m / dt) - f;
  const Vec3 td = (k.w_new - k.w_old) * (inertia / dt) - t;
  acc.drive += 0.5 * (dot(fd_prev + fd, k.v_old) + dot(td_prev + td, k.w_old)) * dt;
  fd_prev = fd;
  td_prev = td;
}

// Adds the shares particle k (local) received from earlier ranks, in the order they came.
inline void add_shares(const IncomingShares<CrossSlot>& in, std::size_t k, Vec3& force,
                       Vec3& torque) noexcept {
  for (std::uint32_t m = in.offsets[k]; m < in.offsets[k + 1]; ++m) {
    force += in.values[m].force;
    torque += in.values[m].torque;
  }
}

// How many particles ahead the integrator asks for the cross slots it will gather.
constexpr std::size_t kCrossAhead = 4;

IntegrateBlock sum_blocks(const std::vector<IntegrateBlock>& blocks) {
  IntegrateBlock total;
  for (const IntegrateBlock& s : blocks) {
    total.local_damping += s.local_damping;
    total.gravity += s.gravity;
    total.drive += s.drive;
    total.external += s.external;
    total.damping_boundary += s.damping_boundary;
    total.external_boundary += s.external_boundary;
    total.ke_t += s.ke_t;
    total.ke_r += s.ke_r;
    total.max_disp2 = std::max(total.max_disp2, s.max_disp2);
  }
  return total;
}

}  // namespace

// Particle i's loads of the step, kept as its totals: its pair and wall sums, the shares of
// pairs owned by earlier ranks, then the cross slots of its earlier own blocks (in one process
// all of these are cross slots, in this order), then its external load (f_user, cleared).
void Simulation::total_loads(const PairList& pairs, std::size_t i, bool has_user_force, Vec3& f,
                             Vec3& t, Vec3& f_user) {
  f = p_.force[i];
  t = p_.torque[i];
  if (split_) add_shares(split_->incoming, i - split_->own.begin, f, t);
  gather_cross(pairs, cross_slots_, i, f, t);
  if (has_user_force) {
    f_user = user_force_[i];
    user_force_[i] = {};
    f += f_user;
  }
  p_.force[i] = f;
  p_.torque[i] = t;
}

template <class CL>
void Simulation::integrate_for(ContactSet<CL>& c, bool sample) {
  const std::size_t n = p_.size();
  block_int_.assign(block_count(n), IntegrateBlock{});
  const bool has_user_force = !user_force_.empty();
  // A particle fixed or driven after the start: its driver force starts from zero.
  if (p_.has_drives() && drive_force_prev_.size() != 2 * n) drive_force_prev_.resize(2 * n);
  const double dt = dt_;
  const double alpha = cfg_.local_damping, alpha_near_crack = cfg_.dynamic_damping_alpha;
  // Dynamic damping: the grains a recent crack reached, until their marks expire.
  const double* const damped_less_until =
      damped_less_until_.empty() ? nullptr : damped_less_until_.data();
  const double now = time_;
  const Vec3 gravity = cfg_.gravity;
  const bool planar = p_.planar();
  const bool turning = !central_forces_only(c);
  const IndexRange own = owned_blocks(owned_particles(), kBlock);
  for_blocks_in(own.begin, own.end, n, [&](std::size_t begin, std::size_t end, std::size_t blk) {
    with_instruction_set(isa_, [&] {
      IntegrateBlock acc;
      for (std::size_t i = begin; i < end; ++i) {
        if (i + kCrossAhead < end) prefetch_cross(c.pairs, cross_slots_, i + kCrossAhead);
        Vec3 f, t, f_user;
        total_loads(c.pairs, i, has_user_force, f, t, f_user);
        const double m = p_.mass[i], inertia = p_.inertia[i];
        f += gravity * m;
        if (planar) {
          f.z = 0.0;
          t.x = 0.0;
          t.y = 0.0;
        }
        if (!turning) t = {};  // the walls' torques too are rounding then
        Kick k{p_.vel[i], p_.angvel[i], {}, {}};
        if (p_.motion[i] == Motion::Free)
          kick_free(f, t, m, inertia, dt,
                    damped_less_until && now < damped_less_until[i] ? alpha_near_crack : alpha,
                    sample, k, acc);
        else
          kick_driven(p_.motion[i] == Motion::Fixed, p_.drive_vel[i], p_.drive_angvel[i], planar, f,
                      t, m, inertia, dt, drive_force_prev_[2 * i], drive_force_prev_[2 * i + 1], k,
                      acc);
        acc.gravity += m * dot(gravity, k.v_old) * dt;
        if (has_user_force) {
          acc.external += 0.5 * dot(f_user, k.v_old + k.v_new) * dt;
          if (sample) acc.external_boundary += 0.5 * dot(f_user, k.v_new) * dt;
        }
        // The drift and the rotation update.
        p_.vel[i] = k.v_new;
        p_.angvel[i] = k.w_new;
        const Vec3 dx = k.v_new * dt;
        p_.pos_rad[i].x += dx;
        p_.displacement[i] += dx;
        if (planar)
          p_.angle[i] += k.w_new.z * dt;
        else if (turning || norm2(k.w_new) > 0.0)  // central forces leave a grain at rest unturned
          p_.orientation[i] = integrate_orientation(p_.orientation[i], k.w_new, dt);
        acc.max_disp2 = std::max(acc.max_disp2, norm2(p_.pos_rad[i].x - x_at_build_[i]));
        if (sample) {
          // Kinetic energy at t_n as leapfrog conserves it: (1/2) m v^{n-1/2} . v^{n+1/2}. With the
          // trapezoidal work rule the balance of §2.4 then closes exactly for linear springs (it
          // differs from (1/2) m v^2 by O(dt^2)).
          acc.ke_t += 0.5 * m * dot(k.v_old, k.v_new);
          acc.ke_r += 0.5 * inertia * dot(k.w_old, k.w_new);
        }
      }
      block_int_[blk] = acc;
    });
  });
  if (split_) {
    // A sampled step's kinetic energy is read within it; the other steps' partials travel with
    // the next step's ghosts (one waiting point fewer a step) and are added at its start.
    if (!sample) {
      split_->integration_pending = true;
      return;
    }
    complete_block_partials(block_int_, kBlock, split_->ranges);
  }
  add_integration_totals(sample);
}

void Simulation::add_integration_totals(bool sample) {
  const IntegrateBlock total = sum_blocks(block_int_);
  d_local_ += total.local_damping;
  w_gravity_ += total.gravity;
  w_drive_ += total.drive;
  w_external_ += total.external;
  max_disp2_ = std::max(max_disp2_, total.max_disp2);
  if (sample) {
    ledger_.kinetic_translational = total.ke_t;
    ledger_.kinetic_rotational = total.ke_r;
    d_local_boundary_ = total.damping_boundary;
    w_external_boundary_ = total.external_boundary;
  }
}

void Simulation::integrate(bool sample) {
  std::visit([&](auto& contacts) { integrate_for(contacts, sample); }, contact_);
}

}  // namespace breccia
