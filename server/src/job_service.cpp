#include "job_service.h"

#include <spdlog/spdlog.h>

#include <cmath>
#include <regex>

#include "mdem/job_runner.h"
#include "mdem/spec.h"
#include "mdem/spec_job.h"
#include "mdem/time_text.h"
#include "queue_place.h"
#include "request_check.h"
#include "study_check.h"

namespace mdem::server {
namespace {

using grpc::Status;
using grpc::StatusCode;

constexpr int kWatchPageEvents = 64;
constexpr std::size_t kWatchPageBytes = 4 << 20;

// The data directory cannot keep a new job: nothing acknowledged may be lost.
Status unavailable(const std::string& why, const char* what_happened) {
  return Status(StatusCode::UNAVAILABLE, "mdemd cannot keep new jobs now: " + why + "; " +
                                             what_happened +
                                             " (health is NOT_SERVING until it is fixed)");
}

Status internal(const std::exception& e) {
  spdlog::error("event=rpc_failed error=\"{}\"", e.what());
  return Status(StatusCode::INTERNAL, std::string("mdemd: ") + e.what());
}

}  // namespace

template <class Body>
Status JobServiceImpl::as_user(const grpc::ServerContext* ctx, Body&& body) const {
  Identity who;
  if (Status s = authenticate(ctx, who); !s.ok()) return s;
  try {
    return body(static_cast<const Identity&>(who));
  } catch (const std::exception& e) {
    return internal(e);
  }
}

Status JobServiceImpl::authenticate(const grpc::ServerContext* ctx, Identity& who) const {
  const auto& md = ctx->client_metadata();
  auto it = md.find("authorization");
  if (it == md.end())
    return Status(StatusCode::UNAUTHENTICATED,
                  "no credentials: send 'authorization: Bearer <token>' (mdem --token-file)");
  const std::string value(it->second.data(), it->second.size());
  const std::string prefix = "Bearer ";
  if (value.rfind(prefix, 0) != 0)
    return Status(StatusCode::UNAUTHENTICATED, "the authorization header is not 'Bearer <token>'");
  auto id = tokens_.find(value.substr(prefix.size()));
  if (!id) return Status(StatusCode::UNAUTHENTICATED, "unknown token");
  who = *id;
  return Status::OK;
}

Status JobServiceImpl::visible_job(const Identity& who, const std::string& id, JobRow& row) {
  if (id.empty()) return Status(StatusCode::INVALID_ARGUMENT, "job_id: required");
  constexpr std::size_t kMaxIdLength = 128;  // job ids are far shorter; never echo a huge one
  if (id.size() > kMaxIdLength)
    return Status(StatusCode::INVALID_ARGUMENT, "job_id: " + std::to_string(id.size()) +
                                                    " characters; at most " +
                                                    std::to_string(kMaxIdLength) + " allowed");
  auto r = store_.get(id);
  if (!r) return Status(StatusCode::NOT_FOUND, "no job '" + id + "'");
  if (r->user != who.user && !who.admin)
    return Status(
        StatusCode::PERMISSION_DENIED,
        "job '" + id + "' belongs to another user; only its owner or an admin may see it");
  row = *r;
  return Status::OK;
}

Status JobServiceImpl::time_limit(double asked, const char* field, double& limit) const {
  if (!std::isfinite(asked) || asked < 0 || asked > kMaxTimeLimitS)
    return Status(StatusCode::INVALID_ARGUMENT,
                  std::string(field) + ": " + std::to_string(asked) + " s is not in (0, " +
                      std::to_string(static_cast<long>(kMaxTimeLimitS)) +
                      "] s (30 days), or 0 for the daemon's default");
  limit = asked > 0 ? asked
                    : (config_.default_time_limit_s > 0 ? config_.default_time_limit_s
                                                        : config_.max_time_limit_s);
  if (config_.max_time_limit_s > 0 && limit > config_.max_time_limit_s)
    return Status(StatusCode::INVALID_ARGUMENT,
                  std::string(field) + ": " + duration_text(limit) +
                      " is above this daemon's limit max_time_limit = " +
                      duration_text(config_.max_time_limit_s) + "; ask for at most that");
  return Status::OK;
}

v1::JobInfo JobServiceImpl::job_info(const JobRow& row, const std::vector<JobOwner>& queue,
                                     const std::vector<JobOwner>& running, const Identity& who) {
  v1::JobInfo info = row.info();
  if (row.state == v1::RUNNING)
    if (const auto u = scheduler_.usage(row.id)) {
      info.set_elapsed_s(u->elapsed_s);
      info.set_job_data_peak_bytes(u->peak_bytes);
      info.set_daemon_rss_peak_bytes(u->daemon_rss_peak_bytes);
    }
  describe_wait(info, queue, running, config_.workers, who);
  return info;
}

Status JobServiceImpl::SubmitJob(grpc::ServerContext* ctx, const v1::SubmitJobRequest* req,
                                 v1::SubmitJobResponse* resp) {
  return as_user(ctx, [&](const Identity& who) -> Status {
    static const std::regex id_re("[A-Za-z0-9._:-]{1,128}");
    if (!std::regex_match(req->request_id(), id_re))
      return Status(StatusCode::INVALID_ARGUMENT,
                    "request_id: '" + req->request_id().substr(0, 200) +
                        "' is not 1..128 characters of [A-Za-z0-9._:-]");
    if (const std::string bad = unreadable_fields(*req); !bad.empty())
      return Status(StatusCode::INVALID_ARGUMENT,
                    "the request has fields mdemd cannot read (unknown, or sent with another "
                    "wire type than declared); nothing was queued:\n" +
                        bad);
    if (const std::string bad = study_run_problem(req->study()); !bad.empty())
      return Status(StatusCode::INVALID_ARGUMENT, bad + "; nothing was queued");
    double limit = 0;
    if (Status s = time_limit(req->time_limit_s(), "time_limit_s", limit); !s.ok()) return s;
    v1::JobSpec spec;
    try {
      spec = spec::finalize(req->spec());
    } catch (const spec::SpecError& e) {
      return Status(StatusCode::INVALID_ARGUMENT, std::string("invalid job spec:\n") + e.what());
    }
    // The element count from the spec alone, before anything is built.
    const long bound = element_bound(spec);
    if (bound > config_.max_elements)
      return Status(StatusCode::RESOURCE_EXHAUSTED,
                    "the job has " + std::to_string(bound) + " elements, above this daemon's " +
                        "limit max_elements = " + std::to_string(config_.max_elements));
    const int threads = spec.run().threads() > 0
                            ? std::min(spec.run().threads(), config_.threads_per_job)
                            : config_.threads_per_job;
    // A quick scene is built here, so a bad time step is refused before anything is queued; a
    // scene that needs a simulation of its own (packing) is built by the worker, which checks
    // the time step and the step limit there (total_steps 0 until then).
    long elements = bound, total_steps = 0;
    if (builds_quickly(spec)) try {
        std::unique_ptr<Job> job = make_spec_job(spec, 1);
        check_time_step(*job);  // refuses a time step above the safe limit
        elements = static_cast<long>(job->system().elements().size());
        total_steps = steps_needed(*job);
      } catch (const std::invalid_argument& e) {  // ConfigError included
        return Status(StatusCode::INVALID_ARGUMENT, std::string("invalid job: ") + e.what());
      } catch (const NumericalError& e) {
        return Status(StatusCode::INVALID_ARGUMENT, std::string("invalid job: ") + e.what());
      }
    if (total_steps > config_.max_steps)
      return Status(StatusCode::RESOURCE_EXHAUSTED,
                    "the job needs " + std::to_string(total_steps) + " steps, above this " +
                        "daemon's limit max_steps = " + std::to_string(config_.max_steps) +
                        "; shorten it or raise dt");
    if (const std::string why = storage_.check(); !why.empty())
      return unavailable(why, "nothing was queued");
    SubmitResult r;
    try {
      r = store_.submit(who.user, req->request_id(), spec, req->study(),
                        std::string(job_kind_name(spec)), elements, total_steps, threads,
                        config_.max_queued_per_user, limit);
    } catch (const LimitError& e) {
      return Status(StatusCode::RESOURCE_EXHAUSTED, e.what());
    } catch (const SqliteError& e) {  // e.g. the disk is full
      const std::string why = storage_.check();
      return unavailable(why.empty() ? e.what() : why + " (" + e.what() + ")",
                         "nothing was queued");
    }
    // Acknowledged only if what was committed is still where a restart will look for it.
    if (const std::string why = storage_.check(); !why.empty())
      return unavailable(why,
                         "the job may not have been kept: submit again with the same "
                         "request id once it is fixed");
    *resp->mutable_job() = r.job.info();
    resp->set_created(r.created);
    if (r.created) {
      spdlog::info("event=job_queued job={} user={} request={} elements={} steps={}", r.job.id,
                   who.user, req->request_id(), elements, total_steps);
      scheduler_.wake();
    }
    return Status::OK;
  });
}

Status JobServiceImpl::GetJob(grpc::ServerContext* ctx, const v1::GetJobRequest* req,
                              v1::JobInfo* resp) {
  return as_user(ctx, [&](const Identity& who) -> Status {
    JobRow row;
    if (Status s = visible_job(who, req->job_id(), row); !s.ok()) return s;
    *resp = row.state == v1::QUEUED ? job_info(row, store_.queue(), store_.running(), who)
                                    : job_info(row, {}, {}, who);
    return Status::OK;
  });
}

Status JobServiceImpl::ListJobs(grpc::ServerContext* ctx, const v1::ListJobsRequest* req,
                                v1::ListJobsResponse* resp) {
  return as_user(ctx, [&](const Identity& who) -> Status {
    if (req->all_users() && !who.admin)
      return Status(StatusCode::PERMISSION_DENIED, "all_users: only admins list everyone's jobs");
    if (req->limit() < 0 || req->limit() > 1000)
      return Status(StatusCode::INVALID_ARGUMENT,
                    "limit: " + std::to_string(req->limit()) + " is not in [0, 1000] (0 = 100)");
    if (!req->study_id().empty())
      if (const std::string bad = study_id_problem(req->study_id(), "study_id"); !bad.empty())
        return Status(StatusCode::INVALID_ARGUMENT, bad);
    const int limit = req->limit() == 0 ? 100 : req->limit();
    const std::vector<JobOwner> queue = store_.queue(), running = store_.running();
    for (const JobRow& r : store_.list(req->all_users() ? "" : who.user, limit, req->study_id())) {
      *resp->add_jobs() = job_info(r, queue, running, who);
    }
    return Status::OK;
  });
}

Status JobServiceImpl::CancelJob(grpc::ServerContext* ctx, const v1::CancelJobRequest* req,
                                 v1::JobInfo* resp) {
  return as_user(ctx, [&](const Identity& who) -> Status {
    JobRow row;
    if (Status s = visible_job(who, req->job_id(), row); !s.ok()) return s;
    if (!row.finished()) {
      const std::string reason = "cancelled by " + who.user;
      if (scheduler_.cancel(row.id, reason))
        spdlog::info("event=job_cancel job={} by={}", row.id, who.user);
      // A running job stops at its next chunk of steps: wait (up to 2 s) to report the outcome.
      const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(2);
      while (std::chrono::steady_clock::now() < deadline) {
        row = *store_.get(row.id);
        if (row.finished()) break;
        hub_.wait(hub_.generation(), std::chrono::milliseconds(50));
      }
    }
    *resp = row.info();
    return Status::OK;
  });
}

Status JobServiceImpl::ResumeJob(grpc::ServerContext* ctx, const v1::ResumeJobRequest* req,
                                 v1::JobInfo* resp) {
  return as_user(ctx, [&](const Identity& who) -> Status {
    JobRow row;
    if (Status s = visible_job(who, req->job_id(), row); !s.ok()) return s;
    double grant = 0;
    if (Status s = time_limit(req->time_limit_s(), "time_limit_s", grant); !s.ok()) return s;
    if (row.state != v1::TIMEOUT)
      return Status(StatusCode::FAILED_PRECONDITION,
                    "job '" + row.id + "' is " + job_state_name(row.state) +
                        "; only a job that ended in TIMEOUT can be resumed");
    if (const std::string why = storage_.check(); !why.empty())
      return unavailable(why, "the job stays in TIMEOUT");
    const std::string reason = "resumed by " + who.user + " from the checkpoint at step " +
                               std::to_string(row.checkpoint_step) + " after " +
                               duration_text(row.wall_s) + " of running time; " +
                               (grant > 0 ? "limit now " + duration_text(row.wall_s + grant) +
                                                " (" + duration_text(grant) + " more)"
                                          : std::string("no time limit"));
    if (!store_.requeue_timeout(row.id, grant, reason))  // it changed meanwhile
      return Status(StatusCode::FAILED_PRECONDITION,
                    "job '" + row.id + "' is no longer in TIMEOUT; only such a job can be resumed");
    spdlog::info("event=job_resume job={} by={} grant_s={:.1f}", row.id, who.user, grant);
    scheduler_.wake();
    *resp = job_info(*store_.get(row.id), store_.queue(), store_.running(), who);
    return Status::OK;
  });
}

Status JobServiceImpl::WatchJob(grpc::ServerContext* ctx, const v1::WatchJobRequest* req,
                                grpc::ServerWriter<v1::JobEvent>* writer) {
  return as_user(ctx, [&](const Identity& who) -> Status {
    JobRow row;
    if (Status s = visible_job(who, req->job_id(), row); !s.ok()) return s;
    if (req->from_seq() < 0 || req->from_seq() > row.last_seq + 1)
      return Status(StatusCode::OUT_OF_RANGE,
                    "from_seq: " + std::to_string(req->from_seq()) + " is not in [0, " +
                        std::to_string(row.last_seq + 1) + "] (the job's next event)");
    long next = std::max<long>(1, req->from_seq());
    while (!ctx->IsCancelled()) {
      const long gen = hub_.generation();
      const auto events = store_.events(row.id, next, kWatchPageEvents, kWatchPageBytes);
      for (const v1::JobEvent& e : events) {
        if (!writer->Write(e)) return Status(StatusCode::CANCELLED, "the watcher went away");
        next = e.seq() + 1;
      }
      if (!events.empty()) continue;
      row = *store_.get(row.id);
      if (row.finished() && next > row.last_seq) return Status::OK;
      hub_.wait(gen, std::chrono::milliseconds(500));
    }
    return Status(StatusCode::CANCELLED, "the watcher went away");
  });
}

}  // namespace mdem::server
