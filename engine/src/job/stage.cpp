// Stages of a job (stage.h).
#include "mdem/job/stage.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "mdem/job/job.h"

namespace mdem {

ForceBalance::ForceBalance(double tolerance) : tolerance_(tolerance) {
  if (!std::isfinite(tolerance) || tolerance <= 0)
    throw std::invalid_argument("force balance tolerance must be finite and > 0 eV/nm, got " +
                                std::to_string(tolerance));
}

double ForceBalance::largest_net_force(const System& sys) {
  const Elements& el = sys.elements();
  double worst = 0;
  for (std::size_t i = 0; i < el.size(); ++i) {
    const auto& dof = el.dof[i];
    if (dof[0] != DofMode::Free && dof[1] != DofMode::Free && dof[2] != DofMode::Free) continue;
    worst = std::max(worst, (el.f[i] + el.f_ext[i]).norm());
  }
  return worst;
}

bool ForceBalance::met(const System& sys) { return largest_net_force(sys) < tolerance_; }

SystemStage::SystemStage(std::string name, Job& job, Settings s)
    : Stage(std::move(name)), job_(job), s_(std::move(s)) {
  const StopCondition& c = s_.stop;
  const bool early = c.criterion && c.duration_ps != 0 && c.steps == 0;  // ends a duration early
  const int kinds = (c.duration_ps != 0) + (c.steps != 0) + (c.criterion != nullptr && !early);
  if (kinds != 1)
    throw std::invalid_argument("stage '" + this->name() +
                                "': the stop condition must be exactly one of a duration, a step "
                                "count or a criterion (a criterion may end a duration early)");
  if (c.duration_ps != 0 && !(std::isfinite(c.duration_ps) && c.duration_ps > 0))
    throw std::invalid_argument("stage '" + this->name() +
                                "': duration must be finite and > 0 ps, got " +
                                std::to_string(c.duration_ps));
  if (c.steps < 0)
    throw std::invalid_argument("stage '" + this->name() + "': steps must be >= 1, got " +
                                std::to_string(c.steps));
  if (c.criterion && (c.check_every < 1 || (!early && c.max_steps < 1)))
    throw std::invalid_argument("stage '" + this->name() +
                                "': a criterion needs check_every >= 1 and, alone, max_steps >= 1");
  if (s_.local_damping && !(*s_.local_damping >= 0 && *s_.local_damping < 1))
    throw std::invalid_argument("stage '" + this->name() + "': local damping must be in [0, 1)");
  for (const auto& o : s_.observers)
    if (!o) throw std::invalid_argument("stage '" + this->name() + "': null observer");
}

System& SystemStage::system() { return job_.system(); }
const System& SystemStage::sys() const { return job_.system(); }

void SystemStage::install() {
  System& sys = system();
  std::vector<std::shared_ptr<Updater>> u;
  if (s_.protocol) u.push_back(s_.protocol);
  u.insert(u.end(), s_.observers.begin(), s_.observers.end());
  sys.set_updaters(std::move(u));
  if (s_.local_damping) sys.set_local_damping(*s_.local_damping);
  sys.set_memory_order(s_.memory_order);
  for (const auto& m : sys.models())
    sys.set_model_active(m.get(), std::find(s_.inactive_models.begin(), s_.inactive_models.end(),
                                            m.get()) == s_.inactive_models.end());
}

void SystemStage::begin() {
  System& sys = system();
  // A system that has run keeps its state: initializing would reset its energy ledger and guard
  // figures. One at step 0 is initialized afresh (callers may have initialized it to check dt).
  // A later stage on a running system re-evaluates the forces at the current state, so that its
  // first step has the stage's damping and models.
  if (sys.steps() == 0 || !sys.initialized())
    sys.initialize();
  else
    sys.refresh_booking_work();
  start_step_ = sys.steps();
  const StopCondition& c = s_.stop;
  if (c.duration_ps > 0)
    end_step_ =
        start_step_ + std::max(1L, static_cast<long>(std::ceil(c.duration_ps / sys.dt() - 1e-9)));
  else if (c.steps > 0)
    end_step_ = start_step_ + c.steps;
  else
    end_step_ = start_step_ + c.max_steps;
  met_ = false;
  begun_ = true;
}

bool SystemStage::finished() const { return met_ || sys().steps() >= end_step_; }

void SystemStage::advance(long steps) {
  System& sys = system();
  long n = std::min(std::max(1L, steps), end_step_ - sys.steps());
  const StopCondition& c = s_.stop;
  if (c.criterion) {
    const long done = sys.steps() - start_step_;
    n = std::min(n, (done / c.check_every + 1) * c.check_every - done);
  }
  if (n <= 0) return;
  sys.run(n);
  if (c.criterion && (sys.steps() - start_step_) % c.check_every == 0) met_ = c.criterion->met(sys);
}

long SystemStage::steps_done() const { return begun_ ? sys().steps() - start_step_ : 0; }

long SystemStage::planned_steps() const {
  if (!begun_) return 0;
  return finished() ? steps_done() : end_step_ - start_step_;
}

std::string SystemStage::phase() const {
  if (s_.protocol) {
    std::string p = s_.protocol->phase(sys().time());
    if (!p.empty()) return p;
  }
  return name();
}

void SystemStage::save_state(StateWriter& w) const {
  sys().save_state(w);
  w.begin("stage");
  w.put(begun_);
  w.put(start_step_);
  w.put(end_step_);
  w.put(met_);
  if (s_.protocol) s_.protocol->save_state(w);
  for (const auto& o : s_.observers) o->save_state(w);
  if (s_.stop.criterion) s_.stop.criterion->save_state(w);
}

void SystemStage::load_state(StateReader& r) {
  // The system's load initializes it, which runs the updaters at the state as built: the
  // protocol's and the observers' state are loaded after it, overwriting what that changed.
  system().load_state(r);
  r.begin("stage");
  begun_ = r.get_bool("begun");
  start_step_ = r.get<long>("start step");
  end_step_ = r.get<long>("end step");
  met_ = r.get_bool("criterion met");
  const long now = sys().steps();
  if (start_step_ < 0 || start_step_ > now || end_step_ < start_step_)
    r.fail("start step", "holds an impossible stage extent");
  if (s_.protocol) s_.protocol->load_state(r);
  for (const auto& o : s_.observers) o->load_state(r);
  if (s_.stop.criterion) s_.stop.criterion->load_state(r);
}

}  // namespace mdem
