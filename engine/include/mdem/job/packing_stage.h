#pragma once
// Packing a particle as a job's first stage (GrainPacker on its own system): progress,
// cancellation and checkpoints while the grains pack, and the packed particle handed on to the
// job, which builds its system from it (Job::stage_finished).
#include <stdexcept>

#include "mdem/job/stage.h"
#include "mdem/scene/grain_packing.h"

namespace mdem {

class PackingStage final : public Stage {
 public:
  explicit PackingStage(const PackingSpec& spec) : Stage("packing"), packer_(spec) {}

  System& system() override { return packer_.system(); }
  bool reports() const override { return false; }
  bool finished() const override { return packer_.done(); }
  // A packing that cannot settle (max_steps, walls closing in too far) fails the job's run as
  // a NumericalError, as any other run that went wrong.
  void advance(long steps) override {
    try {
      packer_.advance(steps);
    } catch (const NumericalError&) {
      throw;
    } catch (const std::runtime_error& e) {
      throw NumericalError(e.what(), packer_.steps(), -1);
    }
  }
  long steps_done() const override { return packer_.steps(); }
  // The packing's step limit until it ends.
  long planned_steps() const override {
    return packer_.done() ? packer_.steps() : packer_.spec().max_steps;
  }
  const PackedParticle& result() const { return packer_.result(); }

  // The packer's state: its progress and system while it runs, the particle once done.
  void save_state(StateWriter& w) const override { packer_.save_state(w); }
  void load_state(StateReader& r) override { packer_.load_state(r); }
  void save_result(StateWriter& w) const override { packer_.save_state(w); }
  void load_result(StateReader& r) override {
    packer_.load_state(r);
    if (!packer_.done()) r.fail("packing", "the checkpoint's packing had not finished");
  }

 private:
  GrainPacker packer_;
};

}  // namespace mdem
