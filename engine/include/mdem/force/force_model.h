#pragma once
// The contract between the system and every force computation (bonds, contacts, dampers).
//
// A model reads element state and writes forces, torques and energy into per-thread slots of a
// ForceSink, so the threaded force loop has no races and sums in a fixed order (deterministic at
// a fixed thread count). A model that acts on pairs within a cutoff declares it, with the pairs of
// element kinds it acts on; the system's pair table (neighbor/pair_table.h) then builds one
// neighbour sub-list (cell list + Verlet skin) per such model, or hands a model that belongs to
// another one's pairs (a contact's dashpot) that model's sub-list. Pair models are written as
// kernels of one pair run by one driver (force/pair_driver.h).
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "mdem/core/domain.h"
#include "mdem/core/elements.h"
#include "mdem/core/energy.h"
#include "mdem/core/index_holder.h"
#include "mdem/neighbor/kind_pairs.h"

namespace mdem {

class NeighborList;
class StateWriter;
class StateReader;

// Loops over fewer items than this run on one thread: waking a team costs more than it saves, and
// on a loaded machine spinning threads can cost far more.
inline constexpr long kParallelMinItems = 2048;

// Per-thread accumulation buffers, reduced into the system's force arrays after all models ran.
// Conservative forces go to force()/torque(); velocity-dependent damping forces go to
// damping_force()/damping_torque(), so the integrator can book the energy they dissipate.
class ForceSink {
 public:
  // with_damping: allocate the damping force buffers (only when some model is dissipative);
  // with_damping_torque: the damping torque buffers too (only when some dissipative model writes
  // torques: none of the dashpots does, and on a film the integrator's pass would otherwise read
  // and zero 24 bytes per element and thread of zeros every step).
  void resize(std::size_t n_elements, int n_threads, bool with_damping,
              bool with_damping_torque = true);
  // Zeroes the buffers (a pass over them only when reduce() did not leave them zero) and the
  // energies, for the models to write.
  void clear();
  int threads() const { return static_cast<int>(force_.size()); }
  Vec3* force(int thread) { return force_[thread].data(); }
  Vec3* torque(int thread) { return torque_[thread].data(); }
  Vec3* damping_force(int thread) { return damp_force_[thread].data(); }
  // Throws std::logic_error when the sink has no damping torque buffers (a dissipative model
  // that writes torques must say so: ForceModel::damping_torques()).
  Vec3* damping_torque(int thread);
  EnergyTally& energy(int thread) { return energy_[thread]; }
  bool has_damping() const { return !damp_force_.empty(); }
  bool has_damping_torque() const { return !damp_torque_.empty(); }
  // Sums all threads in a fixed order into f, t (and fd, td when damping buffers exist; td zero
  // without damping torque buffers),
  // overwriting them, and returns the summed energy tally. Zeroes each buffer entry as it reads
  // it (one pass over the buffers, so the next clear() has none to make): a second reduce()
  // without an evaluation in between returns zero forces.
  EnergyTally reduce(std::vector<Vec3>& f, std::vector<Vec3>& t, std::vector<Vec3>& fd,
                     std::vector<Vec3>& td);
  // reduce() one element at a time, for a caller's own pass over the elements (System::run takes
  // the forces in its integrator pass, which saves the reduction's own parallel region and pass
  // over memory): element i's sums over the threads, in thread order (bit for bit reduce()'s),
  // into f, t, and *fd, *td when damping buffers exist; its buffer entries zeroed as read. After
  // take() of every element, taken() records that the buffers are zero (without it, the next
  // clear() zeroes them again); energy_total() is the summed energy tally, in thread order.
  void take(std::size_t i, Vec3& f, Vec3& t, Vec3* fd, Vec3* td) {
    const int nt = threads();
    take_one(force_, i, nt, f);
    take_one(torque_, i, nt, t);
    if (!damp_force_.empty()) {
      take_one(damp_force_, i, nt, *fd);
      if (!damp_torque_.empty())
        take_one(damp_torque_, i, nt, *td);
      else
        td->setZero();
    }
  }
  void taken() { zeroed_ = true; }
  EnergyTally energy_total() const;
  // Bytes its buffers hold (capacities, every thread's).
  std::size_t memory_bytes() const;

 private:
  static void take_one(std::vector<std::vector<Vec3>>& b, std::size_t i, int nt, Vec3& out) {
    Vec3 sum = b[0][i];
    b[0][i].setZero();
    for (int k = 1; k < nt; ++k) {
      sum += b[k][i];
      b[k][i].setZero();
    }
    out = sum;
  }
  std::vector<std::vector<Vec3>> force_, torque_, damp_force_, damp_torque_;
  std::vector<EnergyTally> energy_;
  bool zeroed_ = true;  // every buffer entry is zero (after resize or reduce)
};

// Upper bounds of the stiffness each element sees, for the critical time step (model.md §7).
// Per element, summed over its interactions: kt translational, kr rotational (eV/rad), ktr the
// translation-rotation coupling (eV/nm/rad, e.g. a shear spring times its lever arm), and c the
// sum of the viscous dashpot coefficients acting on it (eV·ps/nm²).
struct StiffnessSums {
  std::vector<double> kt, kr, ktr, c;
  void reset(std::size_t n) {
    kt.assign(n, 0.0);
    kr.assign(n, 0.0);
    ktr.assign(n, 0.0);
    c.assign(n, 0.0);
  }
  void add_pair(std::size_t i, std::size_t j, double k_t, double k_r, double k_tr) {
    kt[i] += k_t;
    kt[j] += k_t;
    kr[i] += k_r;
    kr[j] += k_r;
    ktr[i] += k_tr;
    ktr[j] += k_tr;
  }
};

// How often multiple time stepping (r-RESPA, IntegratorSettings::respa_k) evaluates a model: Fast
// every inner step (bonds, stiff contacts, walls), Slow once per outer step of respa_k inner steps,
// applied as impulses at the outer step's start and end (soft pair forces: vdW, the NP contacts,
// and the dashpots that damp exactly their pairs).
enum class Timescale { Fast, Slow };

// A model that holds element indices between evaluations remaps them when the system reorders
// its elements (ElementIndexHolder, core/index_holder.h).
class ForceModel : public ElementIndexHolder {
 public:
  virtual std::string_view name() const = 0;

  // > 0: the model acts on element pairs closer than this (nm) and is handed its neighbour
  // sub-list.
  virtual double cutoff() const { return 0.0; }
  // For pair models: the pairs of element kinds the model acts on (its rows of the pair table).
  virtual KindPairs kinds() const { return KindPairs::all(); }
  // For pair models: whether the pair (i, j) is never an interaction of this model (element kinds
  // outside kinds(), or e.g. two segments of one tube within the exclusion). The model's sub-list
  // leaves such pairs out.
  virtual bool excludes(const Elements&, std::size_t, std::size_t) const { return false; }
  // For pair models that belong to another model's pairs (a contact's dashpot acts on exactly the
  // pairs of its contact): that model's name(). The system then hands this model the owner's
  // sub-list; when no such model is present, the model gets a sub-list of its own.
  virtual std::string_view pair_owner() const { return {}; }

  // True for velocity-dependent (damping) models, which write to the sink's damping buffers.
  virtual bool dissipative() const { return false; }
  // True for a dissipative model that writes damping torques (the sink then has their buffers).
  virtual bool damping_torques() const { return false; }
  // Fast unless the model says its forces vary slowly enough for the outer step (Timescale).
  virtual Timescale timescale() const { return Timescale::Fast; }

  // Adds forces, torques and energy of the current state to the sink, using the thread-local
  // slot of omp_get_thread_num() inside its own `#pragma omp parallel for schedule(static)`.
  // `pairs` is null for models with cutoff() == 0.
  virtual void compute(const Elements& el, const NeighborList* pairs, ForceSink& sink) const = 0;
  // For a model whose pairs are `owner`'s (pair_owner() == owner.name(), both handed `pairs`):
  // evaluates owner and this model together in one pass over the list, as owner.compute and
  // compute would one after the other (a dashpot with its contact: one walk, one gather of the
  // far elements for both), and returns true; false when it cannot (the caller then computes each).
  virtual bool compute_with(const ForceModel& /*owner*/, const Elements&, const NeighborList*,
                            ForceSink&) const {
    return false;
  }

  // Adds this model's stiffness bounds at the current state.
  virtual void add_stiffness(const Elements& el, const NeighborList* pairs,
                             StiffnessSums& s) const = 0;

  // The box every displacement of the model is a minimum image in (open until a system binds its
  // own domain at initialize; pair models take it from their sub-list, bonds from here).
  void bind_domain(const Domain* d) { domain_ = d ? d : &kOpenDomain; }
  const Domain& domain() const { return *domain_; }

  // State that changes during a run (a bond's plastic slip, broken flags), for checkpoints; the
  // system saves and loads it in a section named after the model. Stateless models keep these.
  // Bytes of the model's own per-element or per-pair data (bonds, cached axes; capacities), for
  // System::memory_bytes; 0 for a model that holds only parameters.
  virtual std::size_t memory_bytes() const { return 0; }
  virtual void save_state(StateWriter&) const {}
  virtual void load_state(StateReader&) {}

 private:
  const Domain* domain_ = &kOpenDomain;
};

using ForceModelPtr = std::unique_ptr<ForceModel>;

}  // namespace mdem
