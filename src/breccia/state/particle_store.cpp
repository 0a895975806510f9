#include "breccia/state/particle_store.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "breccia/core/archive.hpp"
#include "breccia/core/error.hpp"
#include "breccia/core/format.hpp"

namespace breccia {

ParticleStore::ParticleStore(Dimension dim, double thickness, PlanarBody body)
    : dim_(dim), thickness_(thickness), body_(body) {
  if (!(thickness > 0.0) || !std::isfinite(thickness))
    throw InputError("particle store", "thickness", num(thickness), "must be a finite value > 0 m");
}

double ParticleStore::mass_of(double radius, double rho) const noexcept {
  if (dim_ == Dimension::Two && body_ == PlanarBody::Disk)
    return rho * std::numbers::pi * radius * radius * thickness_;
  return rho * 4.0 / 3.0 * std::numbers::pi * radius * radius * radius;
}

double ParticleStore::inertia_of(double m, double radius) const noexcept {
  if (dim_ == Dimension::Two && body_ == PlanarBody::Disk) return 0.5 * m * radius * radius;
  return 0.4 * m * radius * radius;
}

std::size_t ParticleStore::add(const ParticleSpec& p) {
  const std::string where = "particle " + std::to_string(p.tag);
  if (index_.contains(p.tag))
    throw InputError(where, "tag", std::to_string(p.tag), "tags must be unique");
  if (!(p.radius > 0.0) || !std::isfinite(p.radius))
    throw InputError(where, "radius", num(p.radius), "must be a finite value > 0 m");
  if (!(p.density > 0.0) || !std::isfinite(p.density))
    throw InputError(where, "density", num(p.density), "must be a finite value > 0 kg/m^3");
  for (int k = 0; k < 3; ++k) {
    if (!std::isfinite(p.position[k]) || !std::isfinite(p.velocity[k]) ||
        !std::isfinite(p.angular_velocity[k]))
      throw InputError(where, "position/velocity", "non-finite", "must be finite numbers");
  }
  Vec3 x = p.position, v = p.velocity, w = p.angular_velocity;
  if (planar()) {
    if (x.z != 0.0 || v.z != 0.0 || w.x != 0.0 || w.y != 0.0)
      throw InputError(where, "z / out-of-plane rotation",
                       num(x.z) + " / " + num(w.x) + "," + num(w.y),
                       "2D particles lie in the x-y plane: z, vz, wx and wy must be 0");
  }
  const std::size_t i = size();
  if (i >= TagIndex::kAbsent)
    throw InputError(where, "particles", std::to_string(i + 1),
                     "at most 4294967294 particles (indexes are 32-bit)");
  index_.insert(p.tag, i);
  pos_rad.push_back({x, p.radius});
  vel.push_back(v);
  angvel.push_back(w);
  force.push_back({});
  torque.push_back({});
  const double m = mass_of(p.radius, p.density);
  mass.push_back(m);
  inertia.push_back(inertia_of(m, p.radius));
  density.push_back(p.density);
  orientation.push_back({});
  if (planar()) angle.push_back(0.0);
  displacement.push_back({});
  motion.push_back(Motion::Free);
  if (has_drives()) {
    drive_vel.emplace_back();
    drive_angvel.emplace_back();
  }
  tag.push_back(p.tag);
  set_motion(i, p.motion);
  if (p.motion == Motion::Driven) {
    drive_vel[i] = v;
    drive_angvel[i] = w;
  }
  return i;
}

void ParticleStore::reserve(std::size_t n) {
  for (auto* v : {&vel, &angvel, &force, &torque, &displacement}) v->reserve(n);
  for (auto* v : {&mass, &inertia, &density}) v->reserve(n);
  pos_rad.reserve(n);
  orientation.reserve(n);
  if (planar()) angle.reserve(n);
  tag.reserve(n);
  motion.reserve(n);
  index_.reserve(n);
}

void ParticleStore::set_motion(std::size_t i, Motion m) {
  if (m != Motion::Free && !has_drives()) {
    drive_vel.assign(motion.size(), Vec3{});
    drive_angvel.assign(motion.size(), Vec3{});
  }
  motion[i] = m;
}

std::size_t ParticleStore::index_of(std::uint64_t t, const std::string& where) const {
  const auto i = index_.find(t);
  if (!i) throw InputError(where, "particle tag", std::to_string(t), "no particle has this tag");
  return *i;
}

// One field list for writing and reading: a checkpoint cannot write what it does not read.
template <class Archive>
void ParticleStore::transfer(Archive& a) {
  a.label("particles");
  a.value(dim_);
  a.value(thickness_);
  a.value(body_);
  a.vector(pos_rad);
  a.vector(vel);
  a.vector(angvel);
  a.vector(force);
  a.vector(torque);
  a.vector(mass);
  a.vector(inertia);
  a.vector(density);
  a.vector(orientation);
  a.vector(angle);
  a.vector(displacement);
  a.vector(tag);
  a.vector(motion);
  a.vector(drive_vel);
  a.vector(drive_angvel);
}

void ParticleStore::save(ArchiveWriter& a) const {
  const_cast<ParticleStore*>(this)->transfer(a);  // the writer only reads the fields
}

void ParticleStore::load(ArchiveReader& a) {
  transfer(a);
  const std::size_t n = tag.size();
  // The 2D angles exist in 2D only, the prescribed velocities once a particle is not free.
  const std::size_t angles = planar() ? n : 0;
  const std::size_t drives = has_drives() ? n : 0;
  const bool all_free =
      std::all_of(motion.begin(), motion.end(), [](Motion m) { return m == Motion::Free; });
  for (const std::size_t m :
       {pos_rad.size(), vel.size(), angvel.size(), force.size(), torque.size(), mass.size(),
        inertia.size(), density.size(), orientation.size(), angle.size() + n - angles,
        displacement.size(), motion.size(), drive_vel.size() + n - drives,
        drive_angvel.size() + n - drives})
    if (m != n)
      throw InputError(a.where(), "particles", std::to_string(m),
                       "array lengths differ: the checkpoint is corrupt");
  if (drives == 0 && !all_free)
    throw InputError(a.where(), "particles", "no prescribed velocities",
                     "some grains are fixed or driven: the checkpoint is corrupt");
  index_.clear();
  for (std::size_t i = 0; i < n; ++i) {
    if (index_.contains(tag[i]))
      throw InputError(a.where(), "particles", std::to_string(tag[i]),
                       "a tag appears twice: the checkpoint is corrupt");
    index_.insert(tag[i], i);
  }
}

}  // namespace breccia
