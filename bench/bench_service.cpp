// mdemd service benchmark: a plain timed program (not Google Benchmark: what it measures is a
// separate daemon process). It starts its own mdemd on 127.0.0.1:0 with a temp data directory and
// token file, and measures
//
//   1. latency: SubmitJob to the client receiving (a) the first event of a WatchJob opened as soon
//      as the submit returns, (b) the RUNNING state event, (c) the first energy frame, and (d) the
//      end of the stream; median and p90 over small jobs run one after another;
//   2. fan-out: one job with many events (a frame every 0.02 ps, a snapshot every 1 ps) followed
//      live from seq 1 by N concurrent watchers (own connection each), then the finished job's log
//      replayed by N watchers and by one: events/s in total and per watcher, bytes/s, and a check
//      that every watcher got the same contiguous seq list 1..last_seq;
//   3. overhead: the same job run in-process exactly as `mdem run twist --json` runs it (the CLI's
//      own code, mdem::cli::run, or the mdem binary with --embedded cli) and through mdemd (submit,
//      watch to the end): the report's performance.wall_s and the end-to-end wall of each.
//
// Usage: bench_service [--workers N] [--threads-per-job M] [--quick] [--latency-jobs N]
//                      [--watchers N] [--embedded inproc|cli] [--only 1,2,3] [--keep]
// Prints a table per part and, last, one JSON line. OMP_WAIT_POLICY=PASSIVE is set (the program
// re-executes itself when it is missing) so idle OpenMP threads do not spin on a shared machine.
#include <fcntl.h>
#include <grpcpp/grpcpp.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <sstream>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "daemon.h"
#include "mdem/cli.h"
#include "mdem/v1/service.grpc.pb.h"

namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;
using Json = nlohmann::ordered_json;
using mdem::v1::JobEvent;

double ms_since(Clock::time_point t0, Clock::time_point t = Clock::now()) {
  return std::chrono::duration<double, std::milli>(t - t0).count();
}

std::string loadavg() {
  std::ifstream in("/proc/loadavg");
  double a = 0, b = 0, c = 0;
  in >> a >> b >> c;
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.2f %.2f %.2f", a, b, c);
  return buf;
}

// ---------------------------------------------------------------------------------------------
// Options

struct Options {
  int workers = 1, threads_per_job = 1;
  bool quick = false, keep = false;
  int latency_jobs = 20, watchers = 20;
  std::string embedded = "inproc";  // or "cli"
  std::string only = "123";
};

[[noreturn]] void usage(const std::string& msg) {
  if (!msg.empty()) std::fprintf(stderr, "bench_service: %s\n", msg.c_str());
  std::fprintf(stderr,
               "Usage: bench_service [--workers N] [--threads-per-job M] [--quick]\n"
               "                     [--latency-jobs N] [--watchers N] [--embedded inproc|cli]\n"
               "                     [--only 1,2,3] [--keep]\n"
               "  --workers, --threads-per-job  mdemd's flags (default 1 and 1)\n"
               "  --quick           a small job for part 3 instead of the README's main job\n"
               "  --latency-jobs N  small jobs timed in part 1 (default 20)\n"
               "  --watchers N      concurrent watchers in part 2 (default 20)\n"
               "  --embedded        part 3's in-process run: mdem::cli::run in this process\n"
               "                    (inproc, default) or the mdem binary as a subprocess (cli)\n"
               "  --only LIST       parts to run (default 1,2,3)\n"
               "  --keep            keep the temp directory (daemon log, databases)\n");
  std::exit(msg.empty() ? 0 : 2);
}

Options parse_options(int argc, char** argv) {
  Options o;
  auto need = [&](int& i) -> std::string {
    if (i + 1 >= argc) usage(std::string(argv[i]) + " needs a value");
    return argv[++i];
  };
  auto integer = [&](const std::string& flag, const std::string& v, int lo, int hi) {
    char* end = nullptr;
    const long n = std::strtol(v.c_str(), &end, 10);
    if (v.empty() || *end || n < lo || n > hi)
      usage(flag + ": '" + v + "' is not an integer in [" + std::to_string(lo) + ", " +
            std::to_string(hi) + "]");
    return static_cast<int>(n);
  };
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--help" || a == "-h") usage("");
    if (a == "--workers")
      o.workers = integer(a, need(i), 1, 256);
    else if (a == "--threads-per-job")
      o.threads_per_job = integer(a, need(i), 1, 256);
    else if (a == "--quick")
      o.quick = true;
    else if (a == "--keep")
      o.keep = true;
    else if (a == "--latency-jobs")
      o.latency_jobs = integer(a, need(i), 1, 10000);
    else if (a == "--watchers")
      o.watchers = integer(a, need(i), 1, 1000);
    else if (a == "--embedded") {
      o.embedded = need(i);
      if (o.embedded != "inproc" && o.embedded != "cli") usage("--embedded: inproc or cli");
    } else if (a == "--only") {
      o.only.clear();
      for (char c : need(i))
        if (c >= '1' && c <= '3')
          o.only += c;
        else if (c != ',')
          usage("--only: a list of 1, 2, 3");
    } else
      usage("unknown flag '" + a + "'");
  }
  return o;
}

// ---------------------------------------------------------------------------------------------
// The daemon: the service tests' harness (a real mdemd on port 0 in a temp directory).

using Daemon = mdem::testing::DaemonProcess;
const char* kToken = mdem::testing::kAliceToken;

std::unique_ptr<grpc::ClientContext> ctx(double deadline_s = 60) {
  auto c = std::make_unique<grpc::ClientContext>();
  c->AddMetadata("authorization", std::string("Bearer ") + kToken);
  c->set_deadline(std::chrono::system_clock::now() +
                  std::chrono::milliseconds(static_cast<long>(deadline_s * 1000)));
  return c;
}

// ---------------------------------------------------------------------------------------------
// Jobs

struct TwistParams {
  int layers = 2;
  double length_nm = 13.56, torque = 2, rate = 1, hold_ps = 5, temperature_k = 0;
  double energy_every_ps = 1, snapshot_every_ps = 10;
  int threads = 1;
  int seed = 7;

  mdem::v1::JobSpec spec(const std::string& name) const {
    mdem::v1::JobSpec s;
    s.set_name(name);
    s.set_seed(seed);
    s.mutable_run()->set_threads(threads);
    s.mutable_outputs()->set_energy_every_ps(energy_every_ps);
    s.mutable_outputs()->set_snapshot_every_ps(snapshot_every_ps);
    auto* t = s.mutable_twist();
    t->set_layers(layers);
    t->set_length_nm(length_nm);
    t->set_torque_nn_nm(torque);
    t->set_torque_rate_nn_nm_per_ps(rate);
    t->set_hold_ps(hold_ps);
    t->set_temperature_k(temperature_k);
    return s;
  }
  // The same job as `mdem run twist` flags.
  std::vector<std::string> flags(const std::string& name) const {
    auto num = [](double v) {
      std::ostringstream os;
      os.precision(17);
      os << v;
      return os.str();
    };
    return {"--name",           name,
            "--seed",           std::to_string(seed),
            "--threads",        std::to_string(threads),
            "--energy-every",   num(energy_every_ps),
            "--snapshot-every", num(snapshot_every_ps),
            "--layers",         std::to_string(layers),
            "--length",         num(length_nm),
            "--torque",         num(torque),
            "--rate",           num(rate),
            "--hold",           num(hold_ps),
            "--temperature",    num(temperature_k)};
  }
  std::string describe() const {
    char buf[256];
    std::snprintf(buf, sizeof buf,
                  "twist --layers %d --length %g --torque %g --rate %g --hold %g --temperature %g "
                  "--energy-every %g --snapshot-every %g --threads %d",
                  layers, length_nm, torque, rate, hold_ps, temperature_k, energy_every_ps,
                  snapshot_every_ps, threads);
    return buf;
  }
};

std::string submit(const std::shared_ptr<grpc::Channel>& ch, const std::string& rid,
                   const mdem::v1::JobSpec& spec) {
  mdem::v1::SubmitJobRequest req;
  req.set_request_id(rid);
  *req.mutable_spec() = spec;
  mdem::v1::SubmitJobResponse resp;
  auto c = ctx();
  const grpc::Status s = mdem::v1::JobService::NewStub(ch)->SubmitJob(c.get(), req, &resp);
  if (!s.ok()) throw std::runtime_error("SubmitJob: " + s.error_message());
  return resp.job().job_id();
}

mdem::v1::JobInfo get_job(const std::shared_ptr<grpc::Channel>& ch, const std::string& id) {
  mdem::v1::GetJobRequest req;
  req.set_job_id(id);
  mdem::v1::JobInfo info;
  auto c = ctx();
  const grpc::Status s = mdem::v1::JobService::NewStub(ch)->GetJob(c.get(), req, &info);
  if (!s.ok()) throw std::runtime_error("GetJob: " + s.error_message());
  return info;
}

// What one WatchJob delivered; times in ms from t0 (-1: never).
struct Watched {
  grpc::Status status;
  std::vector<long> seqs;
  long events = 0, bytes = 0;
  long frames = 0, snapshot_chunks = 0, progress = 0, states = 0, coalesced = 0;
  double t_first = -1, t_running = -1, t_frame = -1, t_last = -1, t_end = -1;
  std::string report_json;
  std::string final_state;
};

Watched watch(const std::shared_ptr<grpc::Channel>& ch, const std::string& id, long from_seq,
              Clock::time_point t0, bool keep_seqs) {
  Watched w;
  mdem::v1::WatchJobRequest req;
  req.set_job_id(id);
  req.set_from_seq(from_seq);
  auto c = ctx(3600);
  auto stub = mdem::v1::JobService::NewStub(ch);
  auto reader = stub->WatchJob(c.get(), req);
  JobEvent e;
  while (reader->Read(&e)) {
    const double t = ms_since(t0);
    if (w.t_first < 0) w.t_first = t;
    w.t_last = t;
    ++w.events;
    w.bytes += static_cast<long>(e.ByteSizeLong());
    if (keep_seqs) w.seqs.push_back(e.seq());
    switch (e.event_case()) {
      case JobEvent::kState:
        ++w.states;
        if (e.state().state() == mdem::v1::RUNNING && w.t_running < 0) w.t_running = t;
        w.final_state = mdem::v1::JobState_Name(e.state().state());
        break;
      case JobEvent::kFrame:
        ++w.frames;
        if (w.t_frame < 0) w.t_frame = t;
        break;
      case JobEvent::kSnapshot:
        ++w.snapshot_chunks;
        break;
      case JobEvent::kProgress:
        ++w.progress;
        break;
      case JobEvent::kCoalesced:
        ++w.coalesced;
        break;
      case JobEvent::kReport:
        w.report_json = e.report().json();
        break;
      default:
        break;
    }
  }
  w.status = reader->Finish();
  w.t_end = ms_since(t0);
  return w;
}

double quantile(std::vector<double> v, double q) {
  if (v.empty()) return NAN;
  std::sort(v.begin(), v.end());
  const double x = q * static_cast<double>(v.size() - 1);
  const std::size_t k = static_cast<std::size_t>(x);
  if (k + 1 >= v.size()) return v.back();
  return v[k] + (x - static_cast<double>(k)) * (v[k + 1] - v[k]);
}

double report_wall_s(const std::string& report_json) {
  if (report_json.empty()) return NAN;
  const Json r = Json::parse(report_json);
  return r["performance"]["wall_s"].get<double>();
}

// ---------------------------------------------------------------------------------------------
// 1. Latency

Json part_latency(Daemon& d, const Options& o) {
  TwistParams p;  // 7 tubes x 10 segments = 70 elements, 2 ps ramp + 2 ps hold
  p.hold_ps = 2;
  p.temperature_k = 300;
  p.threads = o.threads_per_job;
  std::printf("\n== 1. Submit-to-first-event latency: %d small jobs, one after another ==\n",
              o.latency_jobs);
  std::printf("job: %s (70 elements)\n", p.describe().c_str());
  std::printf("load before: %s\n", loadavg().c_str());
  std::vector<double> submit_ms, first_ms, running_ms, frame_ms, end_ms, job_wall_ms;
  int failures = 0;
  for (int i = 0; i < o.latency_jobs; ++i) {
    const auto ch = d.channel();
    const auto t0 = Clock::now();
    const std::string id =
        submit(ch, "lat-" + std::to_string(getpid()) + "-" + std::to_string(i), p.spec("lat"));
    submit_ms.push_back(ms_since(t0));
    const Watched w = watch(ch, id, 1, t0, false);
    if (!w.status.ok() || w.final_state != "SUCCEEDED" || w.t_running < 0 || w.t_frame < 0) {
      ++failures;
      std::printf("  FAILURE: job %s: status %s, final state %s\n", id.c_str(),
                  w.status.error_message().c_str(), w.final_state.c_str());
      continue;
    }
    first_ms.push_back(w.t_first);
    running_ms.push_back(w.t_running);
    frame_ms.push_back(w.t_frame);
    end_ms.push_back(w.t_last);
    job_wall_ms.push_back(1000 * report_wall_s(w.report_json));
  }
  Json out;
  out["jobs"] = o.latency_jobs;
  out["failures"] = failures;
  std::printf("%-40s %10s %10s %10s %10s\n", "from SubmitJob call to ... [ms]", "median", "p90",
              "min", "max");
  auto row = [&](const char* name, const char* key, const std::vector<double>& v) {
    const double mn = v.empty() ? NAN : *std::min_element(v.begin(), v.end());
    const double mx = v.empty() ? NAN : *std::max_element(v.begin(), v.end());
    std::printf("%-40s %10.2f %10.2f %10.2f %10.2f\n", name, quantile(v, 0.5), quantile(v, 0.9), mn,
                mx);
    out[key] = {{"median_ms", quantile(v, 0.5)},
                {"p90_ms", quantile(v, 0.9)},
                {"min_ms", mn},
                {"max_ms", mx}};
  };
  row("SubmitJob returned", "submit", submit_ms);
  row("(a) first event of the watch", "first_event", first_ms);
  row("(b) RUNNING state event", "running", running_ms);
  row("(c) first energy frame", "first_frame", frame_ms);
  row("(d) last event (job finished)", "last_event", end_ms);
  row("    job's own wall (report wall_s)", "job_wall", job_wall_ms);
  out["load_after"] = loadavg();
  std::printf("load after: %s\n", out["load_after"].get<std::string>().c_str());
  return out;
}

// ---------------------------------------------------------------------------------------------
// 2. Fan-out to concurrent watchers

struct FanOut {
  double wall_ms = 0;
  std::vector<Watched> w;
  double daemon_cpu_s = 0;
};

// N watchers (one connection each) from seq 1 to the end, started together.
FanOut fan_out(Daemon& d, const std::vector<std::shared_ptr<grpc::Channel>>& chans,
               const std::string& id, int n) {
  FanOut f;
  f.w.resize(n);
  std::atomic<int> ready{0};
  std::atomic<bool> go{false};
  Clock::time_point t0;
  std::vector<std::thread> threads;
  for (int k = 0; k < n; ++k)
    threads.emplace_back([&, k] {
      ++ready;
      while (!go.load()) std::this_thread::yield();
      f.w[k] = watch(chans[k], id, 1, t0, true);
    });
  while (ready.load() < n) std::this_thread::yield();
  const double cpu0 = d.cpu_s();
  t0 = Clock::now();
  go = true;
  for (auto& t : threads) t.join();
  f.wall_ms = ms_since(t0);
  f.daemon_cpu_s = d.cpu_s() - cpu0;
  return f;
}

Json fan_out_row(const char* name, const FanOut& f, long last_seq, int& failures) {
  long events = 0, bytes = 0;
  std::vector<double> per_watcher;
  bool same = true;
  const std::vector<long>& ref = f.w.front().seqs;
  for (std::size_t k = 0; k < f.w.size(); ++k) {
    const Watched& w = f.w[k];
    events += w.events;
    bytes += w.bytes;
    per_watcher.push_back(w.events / (w.t_end / 1000));
    bool contiguous = w.status.ok() && static_cast<long>(w.seqs.size()) == last_seq;
    for (std::size_t i = 0; contiguous && i < w.seqs.size(); ++i)
      contiguous = w.seqs[i] == static_cast<long>(i) + 1;
    if (!contiguous) {
      ++failures;
      std::printf("  FAILURE (%s): watcher %zu got %zu events (status '%s'), not seq 1..%ld\n",
                  name, k, w.seqs.size(), w.status.error_message().c_str(), last_seq);
    }
    same = same && w.seqs == ref;
  }
  if (!same) {
    ++failures;
    std::printf("  FAILURE (%s): the watchers' seq lists differ\n", name);
  }
  const double s = f.wall_ms / 1000;
  std::printf("%-18s %8zu %10.3f %12.0f %12.0f %12.0f %10.2f %9.2f %s\n", name, f.w.size(), s,
              events / s, quantile(per_watcher, 0.5), bytes / s / 1e6,
              bytes / static_cast<double>(f.w.size()) / 1e6, f.daemon_cpu_s, same ? "yes" : "NO");
  Json j;
  j["watchers"] = f.w.size();
  j["wall_s"] = s;
  j["events_total"] = events;
  j["events_per_s_total"] = events / s;
  j["events_per_s_per_watcher_median"] = quantile(per_watcher, 0.5);
  j["events_per_s_per_watcher_min"] = *std::min_element(per_watcher.begin(), per_watcher.end());
  j["bytes_per_s_total"] = bytes / s;
  j["bytes_per_watcher"] = bytes / static_cast<double>(f.w.size());
  j["daemon_cpu_s"] = f.daemon_cpu_s;
  j["identical_contiguous"] = same;
  return j;
}

Json part_fan_out(Daemon& d, const Options& o) {
  TwistParams p;  // 19 tubes x 10 segments = 190 elements
  p.layers = 3;
  p.hold_ps = 200;
  p.temperature_k = 300;
  p.energy_every_ps = 0.02;
  p.snapshot_every_ps = 1;
  p.threads = o.threads_per_job;
  std::printf("\n== 2. Events to %d concurrent watchers (own connection each) ==\n", o.watchers);
  std::printf("job: %s (190 elements)\n", p.describe().c_str());
  std::printf("load before: %s\n", loadavg().c_str());
  std::vector<std::shared_ptr<grpc::Channel>> chans;
  for (int k = 0; k < o.watchers; ++k) chans.push_back(d.new_channel());

  const auto t_submit = Clock::now();
  const std::string id = submit(d.channel(), "fan-" + std::to_string(getpid()), p.spec("fan"));
  const FanOut live = fan_out(d, chans, id, o.watchers);
  const double submit_to_end_s = ms_since(t_submit) / 1000;
  const mdem::v1::JobInfo info = get_job(d.channel(), id);
  const long last_seq = info.last_seq();
  const FanOut replay = fan_out(d, chans, id, o.watchers);
  const FanOut replay1 = fan_out(d, chans, id, 1);

  const Watched& w0 = live.w.front();
  const double job_wall_s = report_wall_s(w0.report_json);
  std::printf(
      "job %s: %s, %ld events (%ld frames, %ld snapshot chunks, %ld progress, %ld "
      "states, %ld coalesced), %.1f kB per watcher; job wall %.3f s\n",
      id.c_str(), w0.final_state.c_str(), last_seq, w0.frames, w0.snapshot_chunks, w0.progress,
      w0.states, w0.coalesced, w0.bytes / 1e3, job_wall_s);
  int failures = 0;
  std::printf("%-18s %8s %10s %12s %12s %12s %10s %9s %s\n", "", "watchers", "wall [s]", "events/s",
              "ev/s/watcher", "MB/s total", "MB/watcher", "mdemd cpu", "same seqs");
  Json out;
  out["job_events"] = last_seq;
  out["frames"] = w0.frames;
  out["snapshot_chunks"] = w0.snapshot_chunks;
  out["coalesced_events"] = w0.coalesced;
  out["job_wall_s"] = job_wall_s;
  out["submit_to_last_watcher_s"] = submit_to_end_s;
  out["live"] = fan_out_row("live (from submit)", live, last_seq, failures);
  out["replay"] = fan_out_row("replay (finished)", replay, last_seq, failures);
  out["replay_1"] = fan_out_row("replay, 1 watcher", replay1, last_seq, failures);
  out["failures"] = failures;
  out["daemon_rss_kb"] = d.rss_kb();
  out["load_after"] = loadavg();
  std::printf("contiguity check: %s; mdemd RSS %ld kB; load after: %s\n",
              failures ? "FAILED" : "every watcher got seq 1..last_seq, identical", d.rss_kb(),
              out["load_after"].get<std::string>().c_str());
  return out;
}

// ---------------------------------------------------------------------------------------------
// 3. Daemon overhead against the in-process run

Json part_overhead(Daemon& d, const Options& o, const fs::path& dir) {
  TwistParams p;
  if (o.quick) {  // 19 tubes x 20 segments = 380 elements, 20 ps ramp + 30 ps hold
    p.layers = 3;
    p.length_nm = 27.12;
    p.torque = 20;
    p.hold_ps = 30;
  } else {  // README's main job: 37 tubes x 20 segments = 740 elements, 60 ps ramp + 100 ps hold
    p.layers = 4;
    p.length_nm = 27.12;
    p.torque = 60;
    p.hold_ps = 100;
  }
  p.threads = o.threads_per_job;
  std::printf("\n== 3. Daemon overhead vs in-process run (%s) ==\n",
              o.quick ? "--quick job" : "README main job");
  std::printf("job: %s (spec defaults for the rest, same for both)\n", p.describe().c_str());
  std::printf("load before: %s\n", loadavg().c_str());

  // (a) In-process, exactly as `mdem run twist --json` (results into a fresh local database).
  std::vector<std::string> args = {"twist"};
  for (const auto& f : p.flags("overhead")) args.push_back(f);
  args.insert(args.end(), {"--db", (dir / "embedded.db").string(), "--json"});
  std::string out_text;
  const auto t0 = Clock::now();
  int rc = 0;
  if (o.embedded == "inproc") {
    std::ostringstream out, err;
    rc = mdem::cli::run(args, out, err);
    out_text = out.str();
  } else {
    std::vector<std::string> argv = {MDEM_CLI_PATH, "run"};
    argv.insert(argv.end(), args.begin(), args.end());
    rc = Daemon::run(argv, dir / "embedded.json");
    std::ifstream in(dir / "embedded.json");
    out_text.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  }
  const double emb_total_s = ms_since(t0) / 1000;
  if (rc != 0) throw std::runtime_error("embedded run failed (exit " + std::to_string(rc) + ")");
  const Json emb = Json::parse(out_text);
  const double emb_wall_s = emb["performance"]["wall_s"].get<double>();
  const long steps = emb["performance"]["steps"].get<long>();
  std::printf("load between: %s\n", loadavg().c_str());

  // (b) Through mdemd: submit, watch from seq 1 to the end of the stream.
  const double cpu0 = d.cpu_s();
  const auto t1 = Clock::now();
  const std::string id = submit(d.channel(), "ovh-" + std::to_string(getpid()), p.spec("overhead"));
  const Watched w = watch(d.channel(), id, 1, t1, false);
  const double dmn_total_s = w.t_last / 1000;
  const double daemon_cpu = d.cpu_s() - cpu0;
  if (!w.status.ok() || w.final_state != "SUCCEEDED")
    throw std::runtime_error("daemon run of " + id +
                             " did not succeed: " + w.status.error_message());
  const Json rep = Json::parse(w.report_json);
  const double dmn_wall_s = rep["performance"]["wall_s"].get<double>();
  const long dmn_steps = rep["performance"]["steps"].get<long>();
  const bool same_result = rep["summary"] == emb["summary"];

  auto pct = [](double a, double b) { return 100 * (a / b - 1); };
  std::printf("%-44s %14s %18s\n", "", "job wall_s [s]", "end-to-end [s]");
  std::printf("%-44s %14.3f %18.3f\n",
              o.embedded == "inproc" ? "(a) in-process (mdem::cli::run, --json --db)"
                                     : "(a) mdem run twist --json --db (subprocess)",
              emb_wall_s, emb_total_s);
  std::printf("%-44s %14.3f %18.3f\n", "(b) mdemd (submit -> last watched event)", dmn_wall_s,
              dmn_total_s);
  std::printf("%-44s %13.1f%% %17.1f%%\n", "overhead (b vs a)", pct(dmn_wall_s, emb_wall_s),
              pct(dmn_total_s, emb_total_s));
  std::printf(
      "steps %ld (in-process) / %ld (daemon); %ld events watched; mdemd CPU %.3f s; "
      "summaries identical: %s\n",
      steps, dmn_steps, w.events, daemon_cpu, same_result ? "yes" : "NO");
  Json out;
  out["job"] = p.describe();
  out["embedded_mode"] = o.embedded;
  out["embedded_wall_s"] = emb_wall_s;
  out["embedded_total_s"] = emb_total_s;
  out["daemon_wall_s"] = dmn_wall_s;
  out["daemon_submit_to_last_event_s"] = dmn_total_s;
  out["overhead_wall_pct"] = pct(dmn_wall_s, emb_wall_s);
  out["overhead_total_pct"] = pct(dmn_total_s, emb_total_s);
  out["steps"] = steps;
  out["daemon_events"] = w.events;
  out["daemon_cpu_s"] = daemon_cpu;
  out["summaries_identical"] = same_result;
  out["load_after"] = loadavg();
  std::printf("load after: %s\n", out["load_after"].get<std::string>().c_str());
  return out;
}

}  // namespace

int main(int argc, char** argv) {
  // libgomp reads OMP_WAIT_POLICY when it is loaded: set it by re-executing this program.
  if (!std::getenv("OMP_WAIT_POLICY")) {
    ::setenv("OMP_WAIT_POLICY", "PASSIVE", 1);
    ::execv("/proc/self/exe", argv);
  }
  const Options o = parse_options(argc, argv);
  ::signal(SIGPIPE, SIG_IGN);
  const fs::path dir =
      fs::temp_directory_path() / ("mdem-bench-service-" + std::to_string(getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  Json doc;
  doc["bench"] = "service";
  int failures = 0;
  try {
    std::printf("mdemd: %s --workers %d --threads-per-job %d\n", MDEMD_PATH, o.workers,
                o.threads_per_job);
    std::printf("OMP_WAIT_POLICY=%s, %u hardware threads, load (1/5/15 min): %s\n",
                std::getenv("OMP_WAIT_POLICY"), std::thread::hardware_concurrency(),
                loadavg().c_str());
    doc["workers"] = o.workers;
    doc["threads_per_job"] = o.threads_per_job;
    doc["quick"] = o.quick;
    doc["load_start"] = loadavg();
    Daemon d(dir, {"--workers", std::to_string(o.workers), "--threads-per-job",
                   std::to_string(o.threads_per_job)});
    // Warm the connection so part 1 times no connection setup.
    {
      mdem::v1::ListJobsRequest req;
      mdem::v1::ListJobsResponse resp;
      auto c = ctx();
      mdem::v1::JobService::NewStub(d.channel())->ListJobs(c.get(), req, &resp);
    }
    if (o.only.find('1') != std::string::npos) {
      doc["latency"] = part_latency(d, o);
      failures += doc["latency"]["failures"].get<int>();
    }
    if (o.only.find('2') != std::string::npos) {
      doc["fan_out"] = part_fan_out(d, o);
      failures += doc["fan_out"]["failures"].get<int>();
    }
    if (o.only.find('3') != std::string::npos) doc["overhead"] = part_overhead(d, o, dir);
    d.terminate();
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bench_service: error: %s (daemon log in %s)\n", e.what(),
                 (dir / "mdemd.log").c_str());
    return 1;
  }
  doc["failures"] = failures;
  doc["load_end"] = loadavg();
  std::printf("\n%s\n", doc.dump().c_str());
  if (o.keep)
    std::fprintf(stderr, "kept %s\n", dir.c_str());
  else
    fs::remove_all(dir);
  return failures ? 1 : 0;
}
