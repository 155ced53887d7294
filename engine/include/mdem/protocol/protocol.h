#pragma once
// A protocol: what a stage of a job does to the system over time (loads, prescribed motion,
// moving walls). It is an updater, applied before every force evaluation with the time it is
// for, that saves and loads the state a run changes in it (Updater), and says where it is.
#include <string>

#include "mdem/integrate/system.h"

namespace mdem {

class Protocol : public Updater {
 public:
  // A few words on where the protocol is at time t ("loading", "holding"), for progress lines;
  // empty when it has no phases (the stage's name is shown then).
  virtual std::string phase(double /*t*/) const { return {}; }
};

}  // namespace mdem
