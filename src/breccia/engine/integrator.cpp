// The integrator (docs/physics.md §1.3-§1.4, §2.1): gather each particle's pair forces in a fixed
// order, add walls, loads and gravity, local damping, then the leapfrog kick and drift and the
// rotation update.
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

template <class CL>
void Simulation::integrate_for(ContactSet<CL>& c, bool sample) {
  const std::size_t n = p_.size();
  const std::size_t nb = block_count(n);
  block_int_.assign(nb, IntegrateBlock{});
  const bool has_user_force = !user_force_.empty();
  const double dt = dt_;
  const double alpha = cfg_.local_damping;
  const Vec3 gravity = cfg_.gravity;
  const bool planar = p_.planar();
  for_blocks(n, [&](std::size_t begin, std::size_t end, std::size_t blk) {
    IntegrateBlock acc;
    for (std::size_t i = begin; i < end; ++i) {
      Vec3 f = ext_force_[i], t = ext_torque_[i];
      ext_force_[i] = {};
      ext_torque_[i] = {};
      gather_pairs(c.pairs, c.slot, i, f, t);
      Vec3 f_user;
      if (has_user_force) {
        f_user = user_force_[i];
        user_force_[i] = {};
        f += f_user;
      }
      p_.force[i] = f;
      p_.torque[i] = t;
      const double m = p_.mass[i], inertia = p_.inertia[i];
      f += gravity * m;
      if (planar) {
        f.z = 0.0;
        t.x = 0.0;
        t.y = 0.0;
      }
      const Vec3 v_old = p_.vel[i], w_old = p_.angvel[i];
      Vec3 v_new, w_new;
      if (p_.motion[i] == Motion::Free) {
        if (alpha > 0.0) {
          // Cundall local damping, sign tested with the predicted full-step velocity (§2.1).
          const Vec3 vp = v_old + f * (0.5 * dt / m);
          const Vec3 wp = w_old + t * (0.5 * dt / inertia);
          Vec3 fd, td;
          for (int k = 0; k < 3; ++k) {
            fd[k] = -alpha * std::abs(f[k]) * ((vp[k] > 0.0) - (vp[k] < 0.0));
            td[k] = -alpha * std::abs(t[k]) * ((wp[k] > 0.0) - (wp[k] < 0.0));
          }
          f += fd;
          t += td;
          v_new = v_old + f * (dt / m);
          w_new = w_old + t * (dt / inertia);
          // The loss is booked as minus the work of the damping force with the same trapezoidal
          // rule as every other term, (1/2) F_d . (v^{n-1/2} + v^{n+1/2}) dt, so the ledger
          // closes; it equals docs/physics.md's alpha dt sum |F||v~| to O(dt). The half that pairs
          // with v^{n+1/2} belongs to the next interval and is removed from a sample.
          acc.local_damping -= 0.5 * (dot(fd, v_old + v_new) + dot(td, w_old + w_new)) * dt;
          if (sample) acc.damping_boundary -= 0.5 * (dot(fd, v_new) + dot(td, w_new)) * dt;
        } else {
          v_new = v_old + f * (dt / m);
          w_new = w_old + t * (dt / inertia);
        }
        acc.gravity += m * dot(gravity, v_old) * dt;
      } else {
        // Fixed or driven: the driver supplies whatever force keeps the prescribed motion; its
        // work is booked with the trapezoidal rule like the walls'.
        const bool fixed = p_.motion[i] == Motion::Fixed;
        v_new = fixed ? Vec3{} : p_.drive_vel[i];
        w_new = fixed ? Vec3{} : p_.drive_angvel[i];
        if (planar) {
          v_new.z = 0.0;
          w_new.x = 0.0;
          w_new.y = 0.0;
        }
        const Vec3 fd = (v_new - v_old) * (m / dt) - f;
        const Vec3 td = (w_new - w_old) * (inertia / dt) - t;
        Vec3& fd_prev = drive_force_prev_[2 * i];
        Vec3& td_prev = drive_force_prev_[2 * i + 1];
        acc.drive += 0.5 * (dot(fd_prev + fd, v_old) + dot(td_prev + td, w_old)) * dt;
        acc.gravity += m * dot(gravity, v_old) * dt;
        fd_prev = fd;
        td_prev = td;
      }
      if (has_user_force) {
        acc.external += 0.5 * dot(f_user, v_old + v_new) * dt;
        if (sample) acc.external_boundary += 0.5 * dot(f_user, v_new) * dt;
      }
      p_.vel[i] = v_new;
      p_.angvel[i] = w_new;
      const Vec3 dx = v_new * dt;
      p_.pos_rad[i].x += dx;
      p_.displacement[i] += dx;
      if (planar)
        p_.angle[i] += w_new.z * dt;
      else
        p_.orientation[i] = integrate_orientation(p_.orientation[i], w_new, dt);
      acc.max_disp2 = std::max(acc.max_disp2, norm2(p_.pos_rad[i].x - x_at_build_[i]));
      if (sample) {
        // Kinetic energy at t_n as leapfrog conserves it: (1/2) m v^{n-1/2} . v^{n+1/2}. With the
        // trapezoidal work rule the balance of §2.4 then closes exactly for linear springs (it
        // differs from (1/2) m v^2 by O(dt^2)).
        acc.ke_t += 0.5 * m * dot(v_old, v_new);
        acc.ke_r += 0.5 * inertia * dot(w_old, w_new);
      }
    }
    block_int_[blk] = acc;
  });
  IntegrateBlock total;
  for (const IntegrateBlock& s : block_int_) {
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
