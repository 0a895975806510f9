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
struct PosRad;

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

// Flexible membrane around a 3D cylinder (docs/physics.md §6.3): the 2D membrane's rule on a
// surface. The lateral surface between the platens is cut into cells, n_theta around the axis
// (each about one mean grain diameter of arc at the sample's outer radius) by n_z along it (one
// mean diameter tall); in each cell, a wedge through the whole sample, the grain whose surface
// reaches furthest from the axis is the membrane's node there, found afresh every step. A cell
// that holds no grain takes the node of the next cell around the axis that does.
//
// The nodes form a grid closed around the axis, with a ring on each platen under the first row
// and over the last (each ring node takes its column's end grain, moved onto the platen). Each
// grid face a b c d (around the axis, then up) pushes inward with sigma_3 times its area vector,
// (c - a) x (d - b) / 2, a quarter to each corner's grain: the faces tile the membrane however
// the grains lie, so the radial forces sum to sigma_3 times its lateral area and hold the
// confining stress as the sample bulges or a shear band breaks through. On a split sample the
// cells' choices are combined over the ranks as the 2D chains' are. The engine books the loads'
// work as external work.
class MembraneCylinder {
 public:
  // Finds the nodes between the platens at z_bottom and z_top around the axis through `centre`
  // (along z) and sets the loads of the coming step in sim.external_force().
  void apply(Simulation& sim, double sigma3, const Vec3& centre, double z_bottom, double z_top);
  // The confining stress the last apply() put on the sample: the inward radial force over the
  // faces' radial area. Equal to sigma_3 to rounding, reported as measured.
  double stress() const noexcept { return stress_; }
  // The sample's diameter: twice the mean reach of the nodes from the axis, by face area.
  double diameter(const ParticleStore& p) const;
  // Finds the nodes without loading them.
  void find(const ParticleStore& p, const Vec3& centre, double z_bottom, double z_top);
  // The nodes' grains, ascending (as of the last search).
  const std::vector<std::uint32_t>& grains() const noexcept { return grains_; }
  // Cells around the axis and along it (as of the last search).
  std::size_t columns() const noexcept { return columns_; }
  std::size_t rows() const noexcept { return rows_; }

 private:
  // The cells' choices among the grains [from, to).
  // over_ranks: the outer radius that sizes the cells is every rank's largest (collective).
  void find_nodes(const ParticleStore& p, std::size_t from, std::size_t to, bool over_ranks);
  // Each cell's choice over every rank's (collective).
  void choose_over_ranks(const ParticleStore& p);
  // Cells without a grain take the next cell's around the axis; lists the grains.
  void fill_and_list();
  struct FaceSums {
    double inward = 0.0;       // the faces' inward radial force
    double radial_area = 0.0;  // their area vectors' radial components
    double reach = 0.0;        // their corners' mean reach from the axis, times that area
  };
  // The grid's faces and their loads, added into `load` (null: only the sums, for diameter()).
  FaceSums load_faces(const ParticleStore& p, double sigma3, std::vector<Vec3>* load) const;
  // The grain at a grid node: column k, level j (0: the bottom ring, rows_ + 1: the top ring),
  // and where the node is.
  std::uint32_t grain_at(std::size_t k, std::size_t j) const;
  Vec3 node_at(const ParticleStore& p, std::size_t k, std::size_t j) const;
  // How far a grain's surface reaches from the axis.
  double reach(const PosRad& q) const;

  Vec3 centre_;
  double z_bottom_ = 0.0, z_top_ = 0.0;
  std::size_t columns_ = 0, rows_ = 0;
  std::vector<std::int64_t> node_;  // per cell (column + columns_ x row): its grain, -1 for none
  std::vector<std::uint32_t> grains_;
  double stress_ = 0.0;
};

}  // namespace breccia
