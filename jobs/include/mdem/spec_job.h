#pragma once
// A finalized job spec (mdem::spec::finalize) turned into the engine's terms, and the JSON report
// of a finished job. One place for both, so `mdem run` in-process and the daemon's workers build,
// run and report a job identically.
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <string_view>

#include "mdem/job/compression_job.h"
#include "mdem/job/job.h"
#include "mdem/job/tensile_job.h"
#include "mdem/job/twist_job.h"
#include "mdem/job_kinds.h"
#include "mdem/job_state.h"
#include "mdem/v1/job.pb.h"

namespace mdem {

// The twist, compression and tensile jobs' engine specs (internal units; in each kind's own
// <kind>_job_kind.cpp), integrator settings (the kind's local damping) and output cadence of a
// finalized spec.
TwistJobSpec twist_job_spec(const v1::JobSpec& spec);
CompressionJobSpec compression_job_spec(const v1::JobSpec& spec);
TensileJobSpec tensile_job_spec(const v1::JobSpec& spec);
IntegratorSettings integrator_settings(const v1::JobSpec& spec);
JobCadence job_cadence(const v1::JobSpec& spec);

// "twist", "compression" for the kind the spec holds; "" for none.
std::string_view job_kind_name(const v1::JobSpec& spec);
// An upper bound of the job's element count from the spec alone (nothing built), so a daemon
// can refuse an oversized job cheaply. Compression: the grain estimate (its random count stays
// within 1 % + 10 of it) and the two platens.
long element_bound(const v1::JobSpec& spec);
// Whether building the job's scene is quick (twist: a lattice) rather than a simulation of its
// own (compression: packing the grains, minutes for a thesis-size particle). A daemon builds a
// quick job at submit to check its time step and step count, and leaves the others to the worker.
bool builds_quickly(const v1::JobSpec& spec);

// Builds the engine job of a finalized spec. threads > 0 overrides the spec's thread count (the
// daemon gives each job its share of the machine). Throws std::invalid_argument for an impossible
// scene or load and std::invalid_argument for a spec of a kind this build cannot run.
std::unique_ptr<Job> make_spec_job(const v1::JobSpec& spec, int threads = 0);
// The same with another registry of kinds (a test's own).
std::unique_ptr<Job> make_spec_job(const v1::JobSpec& spec, int threads,
                                   const JobKindRegistry& kinds);

// The report of a job that ran (or stopped): {job_id, kind, state, reason?, summary, accuracy,
// performance}. Keys in this order; the summary (in the order of the kind's declared layout) is
// empty for a FAILED job (its state is not a result), and the energy-balance error is left out
// then.
// The summary without a layout: the engine's names in the engine's order.
ReportJson summary_json(const Summary& s);
ReportJson accuracy_json(const System& sys, bool with_balance);
ReportJson performance_json(const System& sys, double wall_s);
// element_steps_per_s over `work` (every system the job ran); steps, threads and data size are
// the current system's, and steps_all_systems is added when the job ran more than one.
ReportJson performance_json(const System& sys, const JobWork& work, double wall_s);
ReportJson job_report(Job& job, const std::string& job_id, JobState state,
                      const std::string& reason, double wall_s);
// The same for a job of `kind` (its name and summary layout), which need not be in job_kinds().
ReportJson job_report(Job& job, const JobKind& kind, const std::string& job_id, JobState state,
                      const std::string& reason, double wall_s);

}  // namespace mdem
