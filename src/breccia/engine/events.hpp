#pragma once
// Events the engine emits while stepping. A CrackRecord is written in the step a bond breaks, with
// the fields docs/physics.md §4.0 defines (forces compression-positive, those computed but not
// applied in the breaking step).
#include <cstdint>
#include <string_view>

#include "breccia/core/vec3.hpp"
#include "breccia/law/pair.hpp"

namespace breccia {

struct CrackRecord {
  std::uint64_t step = 0;
  double time = 0.0;
  std::string_view law;  // name of the bond law (static storage)
  std::uint64_t bond_tag = 0;
  std::uint64_t id1 = 0, id2 = 0;  // id1 < id2
  double R1 = 0.0, R2 = 0.0;
  Vec3 position;  // bond contact point
  Vec3 normal;    // unit normal from 1 to 2
  CrackMode mode = CrackMode::Tensile;
  std::uint8_t unused[7]{};  // named, not padding (core/archive.hpp)
  double bond_radius = 0.0;
  double Fn = 0.0, Fs = 0.0, Mt = 0.0, Mb = 0.0;
  double sigma = 0.0, tau = 0.0;
  double ratio_t = 0.0, ratio_s = 0.0;
  BondEnergy energy;  // released elastic energy by component; energy.total() is E_brk
};

inline std::string_view to_string(CrackMode m) {
  return m == CrackMode::Tensile ? "tensile" : "shear";
}

}  // namespace breccia
