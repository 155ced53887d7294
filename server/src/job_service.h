#pragma once
// mdem.v1.JobService on the sync gRPC API: authentication by bearer token, per-user access,
// spec validation before anything is queued, and WatchJob served from the durable event log (a
// watcher reads at its own pace, so it can neither slow a job nor grow the daemon's memory).
#include "config.h"
#include "event_writer.h"
#include "job_store.h"
#include "mdem/v1/service.grpc.pb.h"
#include "scheduler.h"
#include "storage_health.h"
#include "tokens.h"

namespace mdem::server {

class JobServiceImpl final : public v1::JobService::Service {
 public:
  JobServiceImpl(const DaemonConfig& config, const TokenTable& tokens, JobStore& store,
                 Scheduler& scheduler, const EventHub& hub, StorageHealth& storage)
      : config_(config),
        tokens_(tokens),
        store_(store),
        scheduler_(scheduler),
        hub_(hub),
        storage_(storage) {}

  grpc::Status SubmitJob(grpc::ServerContext* ctx, const v1::SubmitJobRequest* req,
                         v1::SubmitJobResponse* resp) override;
  grpc::Status GetJob(grpc::ServerContext* ctx, const v1::GetJobRequest* req,
                      v1::JobInfo* resp) override;
  grpc::Status ListJobs(grpc::ServerContext* ctx, const v1::ListJobsRequest* req,
                        v1::ListJobsResponse* resp) override;
  grpc::Status CancelJob(grpc::ServerContext* ctx, const v1::CancelJobRequest* req,
                         v1::JobInfo* resp) override;
  grpc::Status WatchJob(grpc::ServerContext* ctx, const v1::WatchJobRequest* req,
                        grpc::ServerWriter<v1::JobEvent>* writer) override;
  grpc::Status ResumeJob(grpc::ServerContext* ctx, const v1::ResumeJobRequest* req,
                         v1::JobInfo* resp) override;

 private:
  // The caller, or UNAUTHENTICATED.
  grpc::Status authenticate(const grpc::ServerContext* ctx, Identity& who) const;
  // Every RPC: authenticates the caller, then runs body(who); an exception it throws becomes
  // INTERNAL (logged), never a dropped connection.
  template <class Body>
  grpc::Status as_user(const grpc::ServerContext* ctx, Body&& body) const;
  // The job if it exists and the caller may see it; NOT_FOUND / PERMISSION_DENIED otherwise.
  grpc::Status visible_job(const Identity& who, const std::string& id, JobRow& row);
  // The wall-time limit a request's time_limit_s (`field`) gives: its own, else the daemon's
  // default or maximum (0 = none); INVALID_ARGUMENT for a value out of range or above the maximum.
  grpc::Status time_limit(double asked, const char* field, double& limit) const;
  // What GetJob and ListJobs say of a job: its row, with a running job's usage as of its last
  // poll and a queued job's place in the queue.
  v1::JobInfo job_info(const JobRow& row, const std::vector<JobOwner>& queue,
                       const std::vector<JobOwner>& running, const Identity& who);

  DaemonConfig config_;
  const TokenTable& tokens_;
  JobStore& store_;
  Scheduler& scheduler_;
  const EventHub& hub_;
  StorageHealth& storage_;  // a submit is acknowledged only while the data directory can keep it
};

}  // namespace mdem::server
