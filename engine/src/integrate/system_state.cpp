// System checkpoints (System::save_state / load_state).
#include <algorithm>
#include <cmath>
#include <cstring>
#include <stdexcept>
#include <string>
#include <utility>

#include "mdem/integrate/system.h"
#include "mdem/io/state_io.h"

namespace mdem {

namespace {

// Element properties no run changes: a checkpoint must hold the same ones as the job it is loaded
// into, which catches a checkpoint of another scene of the same size.
template <class T>
void expect_same(StateReader& r, const std::vector<T>& have, std::string_view field) {
  std::vector<T> saved;
  r.get(saved, field, have.size());
  if (!saved.empty() && std::memcmp(saved.data(), have.data(), saved.size() * sizeof(T)) != 0)
    r.fail(field, "differs from this job's elements (the checkpoint is of another scene)");
}

// The elements' arrays in tag order (whatever their memory order, so a checkpoint reads the same
// with and without reordering; tags first, so one of other elements is named by them), then their
// memory order: the tags in the order the arrays are held, which a resumed run restores.
void save_elements(StateWriter& w, const Elements& el) {
  w.begin("elements");
  w.put(static_cast<std::uint64_t>(el.size()));
  const std::vector<std::uint32_t> order = el.tag_order();
  auto put = [&](const auto& a) {
    auto in_tag_order = a;
    permute(in_tag_order, order);
    w.put(in_tag_order);
  };
  put(el.tag);
  // State, loads and DOF modes (protocols change these), forces of the last evaluation.
  put(el.x);
  put(el.q);
  put(el.v);
  put(el.w);
  put(el.dof);
  put(el.v_prescribed);
  put(el.w_prescribed);
  put(el.f_ext);
  put(el.t_ext);
  put(el.f);
  put(el.t);
  // Properties, to check against the job's.
  put(el.mass);
  put(el.inv_mass);
  put(el.inertia);
  put(el.radius);
  put(el.kind);
  put(el.tube);
  put(el.index);
  w.put(el.tag);  // the memory order
}

// A loaded state is run only if a run could have reached it (a tampered or damaged checkpoint
// whose CRC was made to match is refused, not run): finite positions, orientations, velocities,
// loads and forces, and no element moving more than its radius or turning more than a radian in
// one step of dt - the integrator's own runaway limit.
void check_loaded_elements(const StateReader& r, const Elements& el, double dt) {
  auto element = [](std::size_t i) { return " of element " + std::to_string(i); };
  for (std::size_t i = 0; i < el.size(); ++i) {
    if (!el.x[i].allFinite()) r.fail("x", "is not finite" + element(i));
    if (!el.q[i].coeffs().allFinite() || !(el.q[i].norm() > 0))
      r.fail("q", "is not a finite, non-zero quaternion" + element(i));
    if (!el.v[i].allFinite()) r.fail("v", "is not finite" + element(i));
    if (!el.w[i].allFinite()) r.fail("w", "is not finite" + element(i));
    if (!el.f_ext[i].allFinite() || !el.t_ext[i].allFinite() || !el.f[i].allFinite() ||
        !el.t[i].allFinite())
      r.fail("f", "a force or torque is not finite" + element(i));
    if (!(el.v[i].norm() * dt <= el.radius[i]))
      r.fail("v", std::to_string(el.v[i].norm()) + " nm/ps" + element(i) + " moves it " +
                      std::to_string(el.v[i].norm() * dt) + " nm in one step, more than its " +
                      "radius " + std::to_string(el.radius[i]) + " nm (no stable run has it)");
    if (!(el.w[i].norm() * dt <= 1.0))
      r.fail("w", std::to_string(el.w[i].norm()) + " rad/ps" + element(i) +
                      " turns it more than a radian in one step (no stable run has it)");
  }
}

// Loads into el, which must be in tag order; returns the saved memory order (tags), unchecked.
std::vector<std::uint64_t> load_elements(StateReader& r, Elements& el) {
  r.begin("elements");
  const std::size_t n = el.size();
  const auto saved_n = r.get<std::uint64_t>("element count");
  if (saved_n != n)
    r.fail({}, "checkpoint holds " + std::to_string(saved_n) + " elements, this job builds " +
                   std::to_string(n));
  expect_same(r, el.tag, "tag");
  r.get(el.x, "x", n);
  r.get(el.q, "q", n);
  r.get(el.v, "v", n);
  r.get(el.w, "w", n);
  r.get(el.dof, "dof", n);
  for (const auto& d : el.dof)
    for (DofMode m : d)
      if (static_cast<int>(m) > static_cast<int>(DofMode::Prescribed))
        r.fail("dof", "holds an unknown DOF mode " + std::to_string(static_cast<int>(m)));
  r.get(el.v_prescribed, "v_prescribed", n);
  r.get(el.w_prescribed, "w_prescribed", n);
  r.get(el.f_ext, "f_ext", n);
  r.get(el.t_ext, "t_ext", n);
  r.get(el.f, "f", n);
  r.get(el.t, "t", n);
  expect_same(r, el.mass, "mass");
  expect_same(r, el.inv_mass, "inv_mass");
  expect_same(r, el.inertia, "inertia");
  expect_same(r, el.radius, "radius");
  expect_same(r, el.kind, "kind");
  expect_same(r, el.tube, "tube");
  expect_same(r, el.index, "index");
  std::vector<std::uint64_t> memory;
  r.get(memory, "memory order", n);
  return memory;
}

// The reordering (new_to_old) that puts el, in tag order, into the saved memory order; fails
// unless that order names each of el's tags once.
std::vector<std::uint32_t> saved_order(StateReader& r, const Elements& el,
                                       const std::vector<std::uint64_t>& memory) {
  std::vector<std::uint32_t> new_to_old(memory.size());
  for (std::size_t k = 0; k < memory.size(); ++k) {
    if (memory[k] >= el.next_tag)
      r.fail("memory order",
             "names tag " + std::to_string(memory[k]) + ", which no element of this job holds");
    new_to_old[k] = static_cast<std::uint32_t>(el.index_of(memory[k]));
  }
  if (!is_permutation_of(new_to_old, el.size()))
    r.fail("memory order", "names an element twice (it must list each element once)");
  return new_to_old;
}

// Topology and groups are saved whole and loaded in place of the job's: a resumed job has the
// bonds, rings (and so the intra-tube exclusions) and groups of the checkpoint. The loaded ones
// are re-validated against the elements.
void save_topology(StateWriter& w, const Topology& t) {
  w.begin("topology");
  std::vector<std::uint64_t> a, b;
  std::vector<std::uint8_t> type;
  for (const TopologyBond& bond : t.bonds()) {
    a.push_back(bond.a);
    b.push_back(bond.b);
    type.push_back(static_cast<std::uint8_t>(bond.type));
  }
  w.put(a);
  w.put(b);
  w.put(type);
  w.put(static_cast<std::uint64_t>(t.chains().size()));
  for (const Chain& c : t.chains()) {
    w.put(c.tube);
    w.put(c.parent);
    w.put(c.closed);
    w.put(c.tags);
  }
}

void load_topology(StateReader& r, Elements& el) {
  r.begin("topology");
  std::vector<std::uint64_t> a, b;
  std::vector<std::uint8_t> type;
  r.get(a, "bond first tags");
  r.get(b, "bond second tags", a.size());
  r.get(type, "bond types", a.size());
  Topology t;
  try {
    for (std::size_t k = 0; k < a.size(); ++k) {
      if (type[k] >= kBondTypeCount)
        r.fail("bond types", "holds an unknown bond type " + std::to_string(type[k]));
      t.add_bond(el, a[k], b[k], static_cast<BondType>(type[k]));
    }
  } catch (const std::invalid_argument& e) {
    r.fail("bonds", e.what());
  }
  const auto n_chains = r.get<std::uint64_t>("chain count");
  for (std::uint64_t k = 0; k < n_chains; ++k) {
    Chain c;
    c.tube = r.get<std::int32_t>("chain tube");
    c.parent = r.get<std::int32_t>("chain parent");
    c.closed = r.get_bool("chain closed");
    r.get(c.tags, "chain tags");
    try {
      t.add_chain(el, std::move(c));
    } catch (const std::invalid_argument& e) {
      r.fail("chains", e.what());
    }
  }
  el.topology = std::move(t);
}

void save_groups(StateWriter& w, const Groups& g) {
  w.begin("groups");
  const std::vector<std::string> names = g.names();
  w.put(static_cast<std::uint64_t>(names.size()));
  for (const std::string& name : names) {
    w.put_string(name);
    w.put(g.get(name));
  }
}

void load_groups(StateReader& r, Elements& el) {
  r.begin("groups");
  const auto n = r.get<std::uint64_t>("group count");
  Groups g;
  for (std::uint64_t k = 0; k < n; ++k) {
    std::string name = r.get_string("group name");
    std::vector<std::uint64_t> tags;
    r.get(tags, "group tags");
    for (std::uint64_t tag : tags)
      if (tag >= el.next_tag)
        r.fail("group tags", "group '" + name + "' names tag " + std::to_string(tag) +
                                 ", which no element of this job holds");
    try {
      g.add(std::move(name), std::move(tags));
    } catch (const std::invalid_argument& e) {
      r.fail("group tags", e.what());
    }
  }
  el.groups = std::move(g);
}

void save_ledger(StateWriter& w, const EnergyLedger& L) {
  w.begin("energy");
  w.put(L.potential.stored);
  w.put(L.kinetic_translational);
  w.put(L.kinetic_rotational);
  w.put(L.external_work);
  w.put(L.dissipated);
  w.put(L.initial_total);
}

void load_ledger(StateReader& r, EnergyLedger& L) {
  r.begin("energy");
  L.potential.stored = r.get<decltype(L.potential.stored)>("potential");
  // What the last evaluation released was booked into `dissipated` then; it is not state.
  L.potential.released = 0;
  L.kinetic_translational = r.get<double>("kinetic_translational");
  L.kinetic_rotational = r.get<double>("kinetic_rotational");
  L.external_work = r.get<double>("external_work");
  L.dissipated = r.get<double>("dissipated");
  L.initial_total = r.get<double>("initial_total");
}

}  // namespace

void System::save_state(StateWriter& w) const {
  if (!initialized_)
    throw CheckpointError(
        "cannot checkpoint a system that was never initialized (forces, "
        "energies and dt are not defined yet)");
  w.begin("system");
  w.put(threads_);
  w.put(respa_.k());
  w.put(time_);
  w.put(dt_);
  w.put(dt_critical_);
  w.put(steps_);
  w.put(energy_scale_);
  w.put(initial_kinetic_);
  w.put(initial_stored_);
  save_elements(w, el_);
  save_topology(w, el_.topology);
  save_groups(w, el_.groups);
  save_ledger(w, ledger_);
  w.begin("respa");  // the slow models' energy held between outer steps
  w.put(respa_.tally.stored);
  for (const auto* a : {&respa_.f, &respa_.t, &respa_.fd, &respa_.td}) w.put(*a);
  w.put(respa_.tags);
  w.begin("damping");
  // The *_prev_ arrays are empty today; saved so that bookkeeping using them resumes too.
  for (const auto* a : {&fd_, &td_, &f_prev_, &t_prev_, &fext_prev_, &text_prev_}) w.put(*a);
  // One section per neighbour sub-list of the pair table (one for every scene so far).
  w.put(!pairs_.empty());
  for (const auto& e : pairs_.entries()) e.list->save_state(w);
  w.begin("models");
  w.put(static_cast<std::uint64_t>(models_.size()));
  for (const auto& m : models_) {
    w.begin(m->name());
    m->save_state(w);
  }
}

void System::load_state(StateReader& r) {
  // Sizes the sinks and damping buffers, creates the neighbour list and checks the settings; the
  // state it computes is then overwritten.
  initialize();
  r.begin("system");
  const int threads = r.get<int>("threads");
  if (threads != threads_)
    r.fail("threads", "checkpoint was written running " + std::to_string(threads) +
                          " threads, this system runs " + std::to_string(threads_) +
                          ": a bit-identical resume needs the same thread count");
  const int respa_k = r.get<int>("respa_k");
  if (respa_k != respa_.k())
    r.fail("respa_k", "checkpoint was written with respa_k = " + std::to_string(respa_k) +
                          ", this job runs respa_k = " + std::to_string(respa_.k()) +
                          ": its forces hold the other split (multiple time stepping)");
  time_ = r.get<double>("time");
  dt_ = r.get<double>("dt");
  dt_critical_ = r.get<double>("dt_critical");
  steps_ = r.get<long>("steps");
  if (!std::isfinite(time_) || time_ < 0) r.fail("time", "must be finite and >= 0");
  if (!std::isfinite(dt_) || !(dt_ > 0)) r.fail("dt", "must be finite and > 0");
  if (std::isnan(dt_critical_) || !(dt_critical_ > 0)) r.fail("dt_critical", "must be > 0");
  if (steps_ < 0) r.fail("steps", "must be >= 0");
  energy_scale_ = r.get<double>("energy_scale");
  initial_kinetic_ = r.get<double>("initial_kinetic");
  initial_stored_ = r.get<double>("initial_stored");
  // Elements come in tag order: put this system's in tag order (initialize may have reordered
  // them), load, then restore the memory order the checkpoint was written in. The models must
  // follow (a model's indices may outlive its loaded state: a bond list built from the topology);
  // the updaters need not: the ones installed now are the stage's, which an uninterrupted run
  // installed on elements already in this order (a stage that reordered them had updaters that
  // follow), and whatever state of theirs holds indices is loaded next, as it was saved.
  const auto put_in = [&](const std::vector<std::uint32_t>& order) {
    if (is_identity_order(order)) return;
    if (const std::string why = reorder_blocker(false); !why.empty()) r.fail("memory order", why);
    apply_order(order);
  };
  put_in(el_.tag_order());
  put_in(saved_order(r, el_, load_elements(r, el_)));
  check_loaded_elements(r, el_, dt_);
  load_topology(r, el_);
  load_groups(r, el_);
  load_ledger(r, ledger_);
  r.begin("respa");
  respa_.tally = EnergyTally{};
  respa_.tally.stored = r.get<decltype(respa_.tally.stored)>("slow energy");
  const std::size_t held = respa_.on() ? el_.size() : 0;
  for (auto* a : {&respa_.f, &respa_.t, &respa_.fd, &respa_.td}) r.get(*a, "slow forces", held);
  r.get(respa_.tags, "slow force tags", held);
  if (respa_.on()) {
    std::vector<std::uint64_t> saved = respa_.tags, have = el_.tag;
    std::sort(saved.begin(), saved.end());
    std::sort(have.begin(), have.end());
    if (saved != have) r.fail("slow force tags", "are not the tags of this job's elements");
    respa_.follow(el_);
  }

  r.begin("damping");
  const std::size_t n = el_.size();
  r.get(fd_, "fd", n);
  r.get(td_, "td", n);
  local_damping_was_on_ = true;  // the loaded fd_/td_ may hold local damping
  for (auto* a : {&f_prev_, &t_prev_, &fext_prev_, &text_prev_}) r.get(*a, "work bookkeeping");
  const bool has_list = r.get_bool("has neighbour list");
  if (has_list != !pairs_.empty())
    r.fail("has neighbour list", has_list ? "checkpoint has a neighbour list, this job has none"
                                          : "checkpoint has no neighbour list, this job needs one");
  for (const auto& e : pairs_.entries()) e.list->load_state(r, n);

  r.begin("models");
  const auto n_models = r.get<std::uint64_t>("model count");
  if (n_models != models_.size())
    r.fail("model count", "checkpoint has " + std::to_string(n_models) + " force models, this " +
                              "job has " + std::to_string(models_.size()));
  for (const auto& m : models_) {
    r.begin(m->name());
    m->load_state(r);
  }
  initialized_ = true;
}

}  // namespace mdem
