#pragma once
// The per-kind-pair table (LAMMPS's pair_hybrid map, HOOMD's per-type-pair r_cut): which pair
// models act on which pairs of element kinds, with which cutoff, and over which neighbour
// sub-list.
//
// Each pair model that owns its pairs gets one entry and one sub-list holding only its kind pairs,
// its exclusion applied, and its own cutoff + skin: a long-reach model (an 8 nm nanoparticle
// contact) does not enlarge another model's list. A model that belongs to another's pairs (a
// contact's dashpot, ForceModel::pair_owner()) joins that model's entry and acts on exactly its
// pairs. All sub-lists share the system's domain and skin.
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "mdem/core/domain.h"
#include "mdem/force/force_model.h"
#include "mdem/neighbor/neighbor_list.h"

namespace mdem {

class PairTable {
 public:
  struct Entry {
    KindPairs kinds;                         // the owner's kind pairs
    double cutoff = 0;                       // the owner's cutoff (nm)
    const ForceModel* owner = nullptr;       // the model the sub-list was built for
    std::vector<const ForceModel*> members;  // owner first, then the models that belong to it
    std::unique_ptr<NeighborList> list;
  };

  // (Re)builds the table from the pair models (cutoff() > 0) among `models`, in their order.
  // Throws std::invalid_argument when a model belonging to another has a longer cutoff than its
  // owner (it would miss pairs), or the domain is too small for a model's reach.
  void setup(const std::vector<ForceModelPtr>& models, double skin, const Domain& domain);

  bool empty() const { return entries_.empty(); }
  const std::vector<Entry>& entries() const { return entries_; }
  // The sub-list model m acts on; null for a model that is not a pair model.
  const NeighborList* list_of(const ForceModel* m) const;
  // The entries acting on the kind pair (a, b), in model order.
  std::vector<const Entry*> lookup(ElementKind a, ElementKind b) const;
  // Rebuilds the sub-lists that el's motion has made stale. before_rebuild, when given, runs first
  // whenever some sub-list is stale; when it returns true (it reordered the elements), every
  // sub-list is rebuilt.
  void update(const Elements& el, const std::function<bool()>& before_rebuild = {});
  // Every sub-list is rebuilt at the next update (the elements were reordered).
  void invalidate();
  // The largest cutoff + skin of the sub-lists (the cell width of a memory order); 0 when empty.
  double max_range() const;
  // "CntSegment-CntSegment: anisotropic_vdw + viscous_contact_damping, cutoff 5.424 nm; ..."
  std::string describe() const;

 private:
  std::vector<Entry> entries_;
  std::vector<std::pair<const ForceModel*, const NeighborList*>> index_;
};

}  // namespace mdem
