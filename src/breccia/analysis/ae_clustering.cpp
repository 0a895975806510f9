#include "breccia/analysis/ae_clustering.hpp"

#include <algorithm>
#include <cmath>
#include <iterator>
#include <map>

#include "breccia/core/archive.hpp"
#include "breccia/core/cell_walk.hpp"
#include "breccia/core/error.hpp"
#include "breccia/core/format.hpp"

namespace breccia::analysis {

double shear_wave_speed(double e, double nu, double rho) {
  return std::sqrt(e / (2.0 * (1.0 + nu)) / rho);
}

EventClusterer::EventClusterer(ClusterSettings s) : s_(s) {
  if (s.linkage == Linkage::Grain) return;  // windows come with each crack
  if (s.linkage != Linkage::SourceRadius && s.linkage != Linkage::SourceRegion)
    throw InputError("AE clustering", "linkage", std::to_string(static_cast<int>(s.linkage)),
                     "one of source_radius, grain, source_region");
  if (!(s.source_radius > 0.0) || !std::isfinite(s.source_radius))
    throw InputError("AE clustering", "source_radius", num(s.source_radius), "must be > 0 m");
  if (!(s.duration > 0.0) || !std::isfinite(s.duration))
    throw InputError("AE clustering", "duration", num(s.duration), "must be > 0 s");
}

namespace {
constexpr std::uint32_t kNoEvent = 0xffffffffu;

// Calls f(e) for every event id indexed in the 27 cells (of size h) around x; `key` hashes a cell.
template <class Cells, class Key, class F>
void each_indexed_near(const Cells& cells, double h, const Vec3& x, Key key, F f) {
  for_each_cell_around(x, h, [&](long long a, long long b, long long c) {
    const auto it = cells.find(key(a, b, c));
    if (it == cells.end()) return;
    for (std::size_t e : it->second) f(e);
  });
}
}  // namespace

std::size_t EventClusterer::find(std::size_t e) const {
  while (parent_[e] != e) e = parent_[e];
  return e;
}

std::size_t EventClusterer::event_of(std::size_t crack) const {
  const std::uint32_t e = crack_event_.at(crack);
  return e == kNoEvent ? static_cast<std::size_t>(-1) : find(e);
}

void EventClusterer::index(std::size_t root, const Vec3& x) {
  const double h = s_.source_radius;
  auto& cell = cells_[cell_key(static_cast<long long>(std::floor(x.x / h)),
                               static_cast<long long>(std::floor(x.y / h)),
                               static_cast<long long>(std::floor(x.z / h)))];
  if (std::find(cell.begin(), cell.end(), root) == cell.end()) cell.push_back(root);
}

std::size_t EventClusterer::join(std::size_t id, double deadline, std::vector<std::size_t>& hits) {
  if (id >= kNoEvent)
    throw InputError("AE clustering", "crack", std::to_string(id),
                     "a run clusters at most " + std::to_string(kNoEvent) + " cracks (32-bit ids)");
  std::size_t event;
  if (hits.empty()) {
    event = parent_.size();  // at most one event per crack: below kNoEvent
    parent_.push_back(static_cast<std::uint32_t>(event));
    live_[event].deadline = deadline;
    open_.push_back(event);
  } else {
    std::sort(hits.begin(), hits.end());
    event = hits.front();
    Live& kept = live_.at(event);  // references to a map's elements outlive its rehashes
    for (std::size_t k = 1; k < hits.size(); ++k) {
      const std::size_t gone = hits[k];
      Live& g = live_.at(gone);
      parent_[gone] = static_cast<std::uint32_t>(event);
      kept.deadline = std::max(kept.deadline, g.deadline);
      for (const Member& m : g.members) {
        kept.members.push_back(m);
        index(event, m.x);
      }
      std::vector<std::uint32_t> u;
      std::set_union(kept.touched.begin(), kept.touched.end(), g.touched.begin(), g.touched.end(),
                     std::back_inserter(u));
      kept.touched = std::move(u);
      for (std::uint32_t p : g.touched) touch_index_[p].push_back(event);
      live_.erase(gone);
      open_.erase(std::find(open_.begin(), open_.end(), gone));
      if (merged) merged(event, gone);
    }
  }
  if (crack_event_.size() <= id) crack_event_.resize(id + 1, kNoEvent);
  crack_event_[id] = static_cast<std::uint32_t>(event);
  Live& l = live_.at(event);
  l.deadline = std::max(l.deadline, deadline);
  return event;
}

// Open events with a crack within r_s of x (cells of size r_s).
std::vector<std::size_t> EventClusterer::linked_by_radius(const Vec3& x) {
  const double h = s_.source_radius, r2 = h * h;
  const auto key = [this](long long a, long long b, long long c) { return cell_key(a, b, c); };
  std::vector<std::size_t> hits;
  each_indexed_near(cells_, h, x, key, [&](std::size_t e) {
    const std::size_t root = find(e);
    if (std::find(hits.begin(), hits.end(), root) != hits.end()) return;
    const auto open = live_.find(root);
    if (open == live_.end()) return;  // closed
    for (const Member& m : open->second.members)
      if (norm2(m.x - x) <= r2) {
        hits.push_back(root);
        return;
      }
  });
  return hits;
}

// The open event whose first crack lies nearest x and within r_s (the smaller id on a tie); none
// or one. Only first cracks are indexed under this linkage.
std::vector<std::size_t> EventClusterer::region_holding(const Vec3& x) {
  const double h = s_.source_radius;
  const auto key = [this](long long a, long long b, long long c) { return cell_key(a, b, c); };
  std::size_t best = 0;
  double best_d2 = h * h;
  bool found = false;
  each_indexed_near(cells_, h, x, key, [&](std::size_t e) {
    const auto open = live_.find(e);
    if (open == live_.end()) return;  // closed
    const double d2 = norm2(open->second.members.front().x - x);
    if (d2 < best_d2 || (d2 == best_d2 && (!found || e < best))) {
      best = e;
      best_d2 = d2;
      found = true;
    }
  });
  return found ? std::vector<std::size_t>{best} : std::vector<std::size_t>{};
}

std::size_t EventClusterer::add(std::size_t id, double time, const Vec3& x) {
  close_before(time, closed);
  const bool region = s_.linkage == Linkage::SourceRegion;
  std::vector<std::size_t> hits = region ? region_holding(x) : linked_by_radius(x);
  // A region's window runs from its first crack: joining does not extend it.
  const double deadline =
      region && !hits.empty() ? live_.at(hits.front()).deadline : time + s_.duration;
  const std::size_t event = join(id, deadline, hits);
  Live& l = live_.at(event);
  l.members.push_back({id, x});
  if (!region || l.members.size() == 1) index(event, x);
  return event;
}

std::size_t EventClusterer::add_grain(std::size_t id, double time, double duration,
                                      const std::vector<std::uint32_t>& own,
                                      const std::vector<std::uint32_t>& touched) {
  close_before(time, closed);
  std::vector<std::size_t> hits;
  for (std::uint32_t p : own) {
    const auto it = touch_index_.find(p);
    if (it == touch_index_.end()) continue;
    for (std::size_t e : it->second) {
      const std::size_t root = find(e);
      if (std::find(hits.begin(), hits.end(), root) != hits.end()) continue;
      const auto open = live_.find(root);
      if (open == live_.end()) continue;  // closed
      const std::vector<std::uint32_t>& t = open->second.touched;
      if (std::binary_search(t.begin(), t.end(), p)) hits.push_back(root);
    }
  }
  const std::size_t event = join(id, time + duration, hits);
  std::vector<std::uint32_t> t = touched;
  std::sort(t.begin(), t.end());
  t.erase(std::unique(t.begin(), t.end()), t.end());
  std::vector<std::uint32_t> u;
  Live& l = live_.at(event);
  std::set_union(l.touched.begin(), l.touched.end(), t.begin(), t.end(), std::back_inserter(u));
  l.touched = std::move(u);
  for (std::uint32_t p : t) {
    auto& list = touch_index_[p];
    if (std::find(list.begin(), list.end(), event) == list.end()) list.push_back(event);
  }
  return event;
}

void EventClusterer::close_before(double time, const std::function<void(std::size_t)>& on_close) {
  const auto& closed_cb = on_close ? on_close : closed;
  for (std::size_t k = 0; k < open_.size();) {
    const std::size_t e = open_[k];
    const auto it = live_.find(e);
    if (time > it->second.deadline) {
      open_.erase(open_.begin() + static_cast<std::ptrdiff_t>(k));
      for (std::uint32_t p : it->second.touched) {
        auto& list = touch_index_[p];
        list.erase(std::remove(list.begin(), list.end(), e), list.end());
        if (list.empty()) touch_index_.erase(p);
      }
      live_.erase(it);
      if (closed_cb) closed_cb(e);
    } else {
      ++k;
    }
  }
  // Drop index entries of closed events now and then (they are skipped when found).
  if (cells_.size() > 64 && open_.empty()) cells_.clear();
}

void EventClusterer::close_all(const std::function<void(std::size_t)>& on_close) {
  const auto& closed_cb = on_close ? on_close : closed;
  const std::vector<std::size_t> open = open_;
  open_.clear();
  live_.clear();
  for (std::size_t e : open)
    if (closed_cb) closed_cb(e);
  cells_.clear();
  touch_index_.clear();
}

template <class Archive>
void EventClusterer::transfer(Archive& a) {
  a.label("event clusterer");
  a.value(s_);
  a.vector(parent_);
  a.vector(crack_event_);
  a.vector(open_);
  if constexpr (Archive::reading) {
    const std::size_t n = parent_.size();
    bool ok = true;
    for (std::uint32_t e : parent_) ok = ok && e < n;
    for (std::size_t e : open_) ok = ok && e < n;
    for (std::uint32_t e : crack_event_) ok = ok && (e < n || e == kNoEvent);
    if (!ok) throw InputError(a.where(), "event clusterer", "indices", "the checkpoint is corrupt");
    live_.clear();
  }
  for (std::size_t e : open_) {
    Live& l = live_[e];
    a.value(l.deadline);
    a.sized(l.members, sizeof(std::uint64_t) + sizeof(Vec3));
    for (Member& m : l.members) {
      std::uint64_t crack = m.crack;
      a.value(crack);
      m.crack = crack;
      a.value(m.x);
    }
    a.vector(l.touched);
  }
  if constexpr (Archive::reading) {
    // The cell and grain indexes follow from the open events.
    cells_.clear();
    touch_index_.clear();
    for (std::size_t e : open_) {
      const Live& l = live_.at(e);
      if (s_.linkage == Linkage::SourceRegion) {
        if (!l.members.empty()) index(e, l.members.front().x);  // the first crack only
      } else {
        for (const Member& m : l.members) index(e, m.x);
      }
      for (std::uint32_t p : l.touched) touch_index_[p].push_back(e);
    }
  }
}

void EventClusterer::save(ArchiveWriter& a) const {
  const_cast<EventClusterer*>(this)->transfer(a);  // the writer only reads the fields
}

void EventClusterer::load(ArchiveReader& a) {
  transfer(a);
}

std::vector<std::size_t> cluster_cracks(const std::vector<double>& time,
                                        const std::vector<Vec3>& position, ClusterSettings s) {
  EventClusterer c(s);
  for (std::size_t k = 0; k < time.size(); ++k) c.add(k, time[k], position[k]);
  c.close_all();
  // Renumber roots in order of their first crack.
  std::map<std::size_t, std::size_t> number;
  std::vector<std::size_t> out(time.size());
  for (std::size_t k = 0; k < time.size(); ++k) {
    const std::size_t root = c.event_of(k);
    const auto it = number.emplace(root, number.size()).first;
    out[k] = it->second;
  }
  return out;
}

}  // namespace breccia::analysis
