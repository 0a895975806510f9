#pragma once
// Flexible membrane of a 2D sample (docs/physics.md §6.3, RICEBAL practice, seed 002): the
// confining pressure acts on the outermost chain of grains of each lateral side, found afresh every
// step as the sample deforms, as a follower load per unit length along the chain.
//
// Finding a chain: the sample's height between the platens is cut into bins one mean grain
// diameter tall; in each bin the grain whose surface reaches furthest out on that side joins the
// chain. The chain's polyline runs through the grain centres, from a point on the bottom platen
// below the first grain to a point on the top platen above the last one.
//
// On a sample split over MPI ranks each rank searches its own grains, the ranks' choices are
// combined bin by bin in rank order (the first grain that reaches furthest, as one process's
// search in index order finds it), and the chains' grains are brought from their owners.
//
// Loading it: each segment of the polyline, of length l and unit inward normal n, carries the
// pressure's force sigma_3 t l n (t the thickness), half to each end grain (the end segments
// wholly to their grain). The inward-normal components sum to sigma_3 t (y_top - y_bottom) on
// each side whatever the chain's shape, so the membrane holds the confining stress exactly, also
// after a shear band has kinked the side. The engine books the loads' work as external work.
#include <array>
#include <cstdint>
#include <vector>

#include "breccia/core/vec3.hpp"

namespace breccia {

class Simulation;
class ParticleStore;

class Membrane2D {
 public:
  // Finds the chains between the platens at y_bottom and y_top (the loading axis is y) and sets
  // the loads of the coming step in sim.external_force(). Returns nothing; stress() and width()
  // report what was applied.
  void apply(Simulation& sim, double sigma3, double y_bottom, double y_top);

  // The confining stress the last apply() put on the sample: the inward horizontal force of both
  // chains over 2 (y_top - y_bottom) t. Equal to sigma_3 to rounding, reported as measured.
  double stress() const noexcept { return stress_; }
  // The sample's width between the chains' outer surfaces (chain-length-weighted means).
  double width(const ParticleStore& p) const;
  // The grains of the left (0) and right (1) chains, bottom to top.
  const std::array<std::vector<std::uint32_t>, 2>& chains() const noexcept { return chains_; }
  // Finds the chains and the chain length each grain carries, without loading them.
  void find(const ParticleStore& p, double y_bottom, double y_top);
  // Both chains' grains, ascending (as of the last search).
  const std::vector<std::uint32_t>& chain_grains() const noexcept { return chain_grains_; }

 private:
  // The bins' choices among the grains [from, to).
  void find_chains(const ParticleStore& p, double y_bottom, double y_top, std::size_t from,
                   std::size_t to);
  // Each bin's choice over every rank's (collective).
  void choose_over_ranks(const ParticleStore& p);
  void make_chains();
  // The chain length each grain carries: half of each neighbouring segment, the end segments
  // to the platens wholly.
  void measure_lengths(const ParticleStore& p, double y_bottom, double y_top);

  std::array<std::vector<std::uint32_t>, 2> chains_;
  std::array<std::vector<double>, 2> lengths_;  // the chain length each grain carries
  std::vector<std::int64_t> best_[2];           // per bin: chosen grain, -1 for none
  std::vector<std::uint32_t> chain_grains_;
  double stress_ = 0.0;
};

}  // namespace breccia
