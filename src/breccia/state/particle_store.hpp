#pragma once
// The particle state: plain arrays grouped by how the hot loops read them (ARCHITECTURE.md,
// "Layers"). Identity is the stable tag; indices are positions in these arrays.
#include <cstdint>
#include <string>
#include <vector>

#include "breccia/core/quat.hpp"
#include "breccia/core/vec3.hpp"
#include "breccia/state/tag_index.hpp"

namespace breccia {

class ArchiveWriter;
class ArchiveReader;

enum class Dimension : std::uint8_t { Three = 3, Two = 2 };

// How a 2D particle's mass and inertia are computed (docs/physics.md §1.2, §3.4).
enum class PlanarBody : std::uint8_t {
  Disk,          // disk of thickness t: m = rho pi R^2 t, I = m R^2 / 2 (default)
  PlanarSphere,  // sphere confined to the plane (RICEBAL-style; needed by planar Hertz contacts)
};

// Position and radius packed together: neighbour search and every pair kernel read both.
struct PosRad {
  Vec3 x;
  double r = 0.0;
};
static_assert(sizeof(PosRad) == 32);

enum class Motion : std::uint8_t {
  Free = 0,    // integrated from forces
  Fixed = 1,   // velocity and angular velocity held at zero
  Driven = 2,  // velocity and angular velocity prescribed
};

struct ParticleSpec {
  std::uint64_t tag = 0;
  Vec3 position;
  double radius = 0.0;
  double density = 0.0;
  Vec3 velocity;
  Vec3 angular_velocity;
  Motion motion = Motion::Free;
};

class ParticleStore {
 public:
  ParticleStore() = default;
  ParticleStore(Dimension dim, double thickness, PlanarBody body = PlanarBody::Disk);

  Dimension dimension() const noexcept { return dim_; }
  bool planar() const noexcept { return dim_ == Dimension::Two; }
  double thickness() const noexcept { return thickness_; }
  PlanarBody planar_body() const noexcept { return body_; }
  std::size_t size() const noexcept { return tag.size(); }

  // Adds a particle; throws InputError on a duplicate tag or non-physical values.
  std::size_t add(const ParticleSpec& p);
  // Index of a tag, or throws InputError naming `where`.
  std::size_t index_of(std::uint64_t tag, const std::string& where = "particle store") const;
  bool contains(std::uint64_t t) const { return index_.contains(t); }

  double mass_of(double radius, double density) const noexcept;

  // Checkpoints: every array in order, then the tag index is rebuilt on loading.
  void save(ArchiveWriter& a) const;
  void load(ArchiveReader& a);
  double inertia_of(double mass, double radius) const noexcept;

  // What each particle holds in the arrays below and the tag table (run/memory_budget.cpp), in a
  // 3D sample whose grains are all free.
  static constexpr std::size_t kBytesPerParticle =
      sizeof(PosRad) + 5 * sizeof(Vec3) + 3 * sizeof(double) + sizeof(Quat) +
      sizeof(std::uint64_t) + sizeof(Motion) + 2 * sizeof(std::uint32_t);

  // Room for n particles in every array, so that a sample added grain by grain does not leave
  // the arrays with up to twice the room they need.
  void reserve(std::size_t n);
  // Sets a particle's motion; the prescribed velocities (drive_vel, drive_angvel) exist once a
  // particle is not free, and are zero until the caller sets them.
  void set_motion(std::size_t i, Motion m);
  // Whether the prescribed-velocity arrays exist (some particle is or was fixed or driven).
  bool has_drives() const noexcept { return !drive_vel.empty(); }

  // Grouped arrays (public: the engine's loops read them directly).
  std::vector<PosRad> pos_rad;
  std::vector<Vec3> vel, angvel;    // v^{n-1/2}, omega^{n-1/2} between steps
  std::vector<Vec3> force, torque;  // total force and moment of the last step (before damping)
  std::vector<double> mass, inertia, density;
  std::vector<Quat> orientation;   // 3D orientation; in 2D a rotation about z kept in step
  std::vector<double> angle;       // 2D orientation angle (never wrapped, §1.4); empty in 3D
  std::vector<Vec3> displacement;  // accumulated displacement since the start
  std::vector<std::uint64_t> tag;
  std::vector<Motion> motion;
  // Prescribed velocities of driven particles, one per particle, or empty while every particle
  // is free (48 bytes a grain that a run without driven grains does not hold).
  std::vector<Vec3> drive_vel, drive_angvel;

 private:
  template <class Archive>
  void transfer(Archive& a);
  Dimension dim_ = Dimension::Three;
  double thickness_ = 1.0;
  PlanarBody body_ = PlanarBody::Disk;
  TagIndex index_;
};

}  // namespace breccia
