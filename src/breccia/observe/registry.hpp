#pragma once
// The one list of recorders. Adding a recorder is one new type (observe/recorder.hpp says what
// it provides) and one entry here: the run makes, calls, checkpoints, restores and lists them all
// from this list, in this order.
#include <memory>
#include <stdexcept>
#include <vector>

#include "breccia/core/type_list.hpp"
#include "breccia/observe/ae_monitor.hpp"
#include "breccia/observe/recorder.hpp"
#include "breccia/observe/recorders.hpp"
#include "breccia/observe/snapshots.hpp"
#include "breccia/observe/wall_table.hpp"

namespace breccia {

using RecorderTypes =
    TypeList<HistoryRecorder, CrackRecorder, SnapshotWriter, AeMonitor, WallTable>;

using RecorderList = std::vector<std::unique_ptr<Recorder>>;

// The recorders of a new run, as loading begins.
inline RecorderList make_recorders(const RecorderSetup& setup) {
  RecorderList list;
  for_each_type<RecorderTypes>([&]<class R>() { list.push_back(R::create(setup)); });
  return list;
}

// The recorders of a checkpoint, each restored from its own part in the order they were saved.
inline RecorderList restore_recorders(const RecorderSetup& setup, ArchiveReader& a) {
  RecorderList list;
  for_each_type<RecorderTypes>([&]<class R>() { list.push_back(R::restore(setup, a)); });
  return list;
}

// Writes every recorder's state, in registry order (restore_recorders reads them back).
inline void save_recorders(const RecorderList& list, ArchiveWriter& a) {
  for (const auto& r : list) r->save_state(a);
}

// The recorder of type R in a list (every registered type is in every list).
template <class R>
R& find_recorder(const RecorderList& list) {
  for (const auto& r : list)
    if (r->name() == R::kind) return static_cast<R&>(*r);
  throw std::logic_error("no recorder of this kind in the run");
}

}  // namespace breccia
