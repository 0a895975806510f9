#pragma once
// Space-time clustering of microcracks into acoustic-emission events after Hazzard & Young (2000)
// (docs/analysis.md §4.1): a crack joins an open event when it lies within the source radius r_s of
// any of the event's cracks (single linkage; events it bridges are merged) and follows the event's
// latest crack by at most T_d = 2 r_s / v_r, v_r = 0.5 v_S (the window rolls with each crack).
// Streaming: the run feeds cracks as they happen, so that a recorder can watch the source
// particles of the open events (moment tensors); a finished catalogue is clustered the same way.
#include <cstddef>
#include <cstdint>
#include <functional>
#include <unordered_map>
#include <vector>

#include "breccia/core/vec3.hpp"

namespace breccia {
class ArchiveWriter;
class ArchiveReader;
}  // namespace breccia

namespace breccia::analysis {

// Three linkage rules (docs/analysis.md §4.1): by source radius (the default of the reference:
// within r_s of any crack of the event, window T_d after its latest crack), by grain (option b of
// the reference: the crack shares a particle with, or touches a contact of, the event's particles;
// window T_c = 2 D_c / v_S of its latest cracks, D_c the larger grain's diameter), or by source
// region (the event is the sphere of radius r_s about its first crack, open for T_d after that
// crack: its size and duration are bounded by the source's crossing time, and events never merge).
enum class Linkage { SourceRadius, Grain, SourceRegion };

struct ClusterSettings {
  double source_radius = 0.0;  // r_s, m
  double duration = 0.0;       // T_d, s (source-radius and source-region linkage)
  Linkage linkage = Linkage::SourceRadius;
  std::uint8_t unused[4]{};  // named, not padding (core/archive.hpp)
};

// v_S = sqrt(G / rho) with G = E / (2 (1 + nu)) and rho the bulk density (§4.1), and
// T_d = 4 r_s / v_S (rupture at half the shear-wave speed across the source diameter).
double shear_wave_speed(double youngs_modulus, double poisson, double bulk_density);
inline double event_duration(double source_radius, double shear_speed) {
  return 4.0 * source_radius / shear_speed;
}

class EventClusterer {
 public:
  explicit EventClusterer(ClusterSettings s);

  // Adds crack `id` (ids in order of time; equal times in id order). Returns its event id.
  // Events merged by a bridging crack keep the smallest id; `merged` is called with (kept, gone).
  // Source-radius and source-region linkage:
  std::size_t add(std::size_t id, double time, const Vec3& position);
  // Grain linkage: `own` are the crack's two particles, `touched` those and the particles in
  // contact with them; `duration` is the crack's window T_c.
  std::size_t add_grain(std::size_t id, double time, double duration,
                        const std::vector<std::uint32_t>& own,
                        const std::vector<std::uint32_t>& touched);
  // Closes every open event whose latest crack is more than T_d before `time`; calls `closed`
  // with each closed event id.
  void close_before(double time, const std::function<void(std::size_t)>& closed = {});
  void close_all(const std::function<void(std::size_t)>& closed = {});

  std::function<void(std::size_t kept, std::size_t gone)> merged;
  // Called for events closed inside add() (and by close_before without its own callback).
  std::function<void(std::size_t)> closed;

  // Checkpoints: the open events and the crack-to-event map (the cell index is rebuilt).
  void save(ArchiveWriter& a) const;
  void load(ArchiveReader& a);

  // Final event of every crack added (after merges), and the open events.
  std::size_t event_of(std::size_t crack) const;
  const std::vector<std::size_t>& open_events() const noexcept { return open_; }
  std::size_t events_created() const noexcept { return parent_.size(); }
  const ClusterSettings& settings() const noexcept { return s_; }

 private:
  std::size_t find(std::size_t e) const;
  template <class Archive>
  void transfer(Archive& a);
  struct Member {
    std::size_t crack;
    Vec3 x;
  };
  // What an open event holds; a closed one keeps only its place in the union-find.
  struct Live {
    double deadline = 0.0;               // closes when time exceeds it
    std::vector<Member> members;         // source-radius linkage
    std::vector<std::uint32_t> touched;  // grain linkage: sorted
  };
  ClusterSettings s_;
  // Event and crack ids fit 32 bits: every crack is a bond's, and bonds have 32-bit tags.
  std::vector<std::uint32_t> parent_;           // event merges (union-find over event ids)
  std::vector<std::uint32_t> crack_event_;      // event id at the time each crack was added
  std::unordered_map<std::size_t, Live> live_;  // per open root
  std::unordered_map<std::uint32_t, std::vector<std::size_t>> touch_index_;  // particle -> events
  std::size_t join(std::size_t id, double deadline, std::vector<std::size_t>& hits);
  std::vector<std::size_t> linked_by_radius(const Vec3& x);
  std::vector<std::size_t> region_holding(const Vec3& x);
  std::vector<std::size_t> open_;                                  // open roots
  std::unordered_map<long long, std::vector<std::size_t>> cells_;  // cell -> open roots
  long long cell_key(long long a, long long b, long long c) const noexcept {
    return (a * 73856093LL) ^ (b * 19349663LL) ^ (c * 83492791LL);
  }
  void index(std::size_t root, const Vec3& x);
};

// The events of a finished catalogue (cracks sorted by time): event id per crack, numbered 0.. in
// order of first crack.
std::vector<std::size_t> cluster_cracks(const std::vector<double>& time,
                                        const std::vector<Vec3>& position, ClusterSettings s);

}  // namespace breccia::analysis
