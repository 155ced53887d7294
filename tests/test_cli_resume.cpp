// `mdem run --resume ID` (issue 16): a local job stopped by SIGINT, or killed outright (kill -9)
// while a real `mdem run` process ran it, continues from its checkpoint to the results of a run
// that was never stopped - summary, frames and snapshots equal bit for bit, none missing or
// stored twice - with its log appended to. A job that cannot be resumed (unknown id, finished,
// checkpoint missing, damaged, truncated, of another job, kind or spec, of another engine format,
// or holding a non-finite or huge value) is refused with a message naming what is wrong, and
// nothing is run or changed.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <bit>
#include <chrono>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <limits>
#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <thread>
#include <vector>

#include "../client/src/results_store.h"
#include "daemon.h"
#include "mdem/checkpoint_file.h"
#include "mdem/cli.h"
#include "mdem/job/job.h"
#include "mdem/spec.h"
#include "mdem/spec_job.h"

namespace {

namespace fs = std::filesystem;
using json = nlohmann::json;
using mdem::cli::ResultsStore;
using mdem::cli::StoreError;
using mdem::testing::contains;
using mdem::testing::DaemonProcess;
using mdem::testing::fresh_dir;
using mdem::testing::slurp;
using Clock = std::chrono::steady_clock;
using mdem::testing::clear_mdem_env;
using mdem::testing::since;
using mdem::testing::operator+;

using Args = std::vector<std::string>;

// A small twist (7 tubes of 10 segments), long enough to be stopped halfway, with snapshots.
// It runs ~1 s on an idle core: long against the 0.1 s checkpoint interval, so the run cannot end
// before the test has seen a checkpoint and stops it (with a 60 ps hold it ran 0.11 s and a fast
// machine finished it first).
const Args kTwist = {"twist", "--layers", "2",   "--length",  "13.56", "--torque",
                     "2",     "--hold",   "600", "--threads", "1",     "--snapshot-every",
                     "100"};
// The refusals' subject, stopped long before its end: the same job with a hold ten times longer.
const Args kTwistLong = {"twist", "--layers", "2",    "--length",  "13.56", "--torque",
                         "2",     "--hold",   "6000", "--threads", "1",     "--snapshot-every",
                         "100"};
// A tiny tensile film (16 tubes of 40 segments, 8 NPs) through all its stages: relaxation,
// deposit, NP pre-relaxation, ramp and straining; the stages restart their step count.
const Args kTensile = {
    "tensile", "--side",           "60",   "--tubes", "16", "--segments",   "40", "--nps",
    "8",       "--prerelax",       "5",    "--relax", "10", "--grip-width", "10", "--strain",
    "1",       "--rate",           "1e-3", "--ramp",  "10", "--threads",    "1",  "--seed",
    "3",       "--snapshot-every", "10"};

Args mdem_cmd(const Args& args) { return Args{MDEM_CLI_PATH, "run"} + args; }

// The only job of a database.
std::string only_job(const std::string& db) {
  const auto jobs = ResultsStore(db).list();
  EXPECT_EQ(jobs.size(), 1u);
  return jobs.empty() ? "" : jobs.front().id;
}

// A run of `args` to its end in its own process: the job id.
std::string run_to_end(const fs::path& dir, const Args& args, const std::string& db) {
  const int code =
      DaemonProcess::run(mdem_cmd(args + Args{"--db", db}), dir / "ref.out", dir / "ref.err");
  EXPECT_EQ(code, 0) << slurp(dir / "ref.err");
  return only_job(db);
}

// Starts `mdem run` and waits until it has written a checkpoint and stored `frames` frames: its
// pid and the job's id (pid -1 when it ended first).
std::pair<int, std::string> start_until_checkpoint(const fs::path& dir, const Args& args,
                                                   const std::string& db, std::size_t frames) {
  const int pid =
      DaemonProcess::spawn(mdem_cmd(args + Args{"--db", db, "--checkpoint-every", "0.1"}),
                           dir / "run.out", dir / "run.err", true);
  const auto t0 = Clock::now();
  while (since(t0) < 60) {
    int status = 0;
    if (::waitpid(pid, &status, WNOHANG) == pid) break;
    try {
      if (fs::exists(db)) {
        ResultsStore store(db);
        const auto jobs = store.list();
        if (!jobs.empty() && store.frame_count(jobs.front().id) >= frames &&
            fs::exists(dir / "checkpoints" / (jobs.front().id + ".ckpt")))
          return {pid, jobs.front().id};
      }
    } catch (const StoreError&) {  // being created
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  ADD_FAILURE() << "mdem run ended or stored nothing before a checkpoint: "
                << slurp(dir / "run.err");
  ::kill(pid, SIGKILL);
  ::waitpid(pid, nullptr, 0);
  return {-1, ""};
}

// Sends `sig` and waits: the exit code (-1 when the signal ended it).
int stop(int pid, int sig) {
  ::kill(pid, sig);
  int status = 0;
  ::waitpid(pid, &status, 0);
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

mdem::testing::CliResult resume(const fs::path& dir, const Args& more) {
  const int code = DaemonProcess::run(Args{MDEM_CLI_PATH, "run", "--resume"} + more,
                                      dir / "resume.out", dir / "resume.err");
  return {code, slurp(dir / "resume.out"), slurp(dir / "resume.err")};
}

bool same_bits(double a, double b) {
  return std::bit_cast<std::uint64_t>(a) == std::bit_cast<std::uint64_t>(b);
}

template <class V>
bool same_bits(const std::vector<V>& a, const std::vector<V>& b) {
  return a.size() == b.size() &&
         (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(V)) == 0);
}

// The results of job `id` in `db` equal those of `ref_id` in `ref_db` bit for bit: every frame
// and snapshot in order (none missing, none twice), and the summary and accuracy of the report.
void expect_same_results(const std::string& ref_db, const std::string& ref_id,
                         const std::string& db, const std::string& id) {
  const ResultsStore ref(ref_db), got(db);
  const auto rf = ref.frames(ref_id), gf = got.frames(id);
  ASSERT_EQ(gf.size(), rf.size()) << "frames";
  for (std::size_t k = 0; k < rf.size(); ++k) {
    EXPECT_EQ(gf[k].step, rf[k].step) << "frame " << k;
    EXPECT_TRUE(same_bits(gf[k].time_ps, rf[k].time_ps)) << "frame " << k;
    EXPECT_TRUE(same_bits(gf[k].values, rf[k].values)) << "frame " << k << " step " << rf[k].step;
  }
  const auto rs = ref.snapshots(ref_id), gs = got.snapshots(id);
  ASSERT_EQ(gs.size(), rs.size()) << "snapshots";
  for (std::size_t k = 0; k < rs.size(); ++k) {
    EXPECT_EQ(gs[k].step, rs[k].step) << "snapshot " << k;
    EXPECT_TRUE(same_bits(gs[k].x, rs[k].x)) << "snapshot " << k;
    EXPECT_TRUE(same_bits(gs[k].q, rs[k].q)) << "snapshot " << k;
    EXPECT_TRUE(same_bits(gs[k].v, rs[k].v)) << "snapshot " << k;
    ASSERT_EQ(gs[k].scalars.size(), rs[k].scalars.size());
    for (std::size_t s = 0; s < rs[k].scalars.size(); ++s)
      EXPECT_TRUE(same_bits(gs[k].scalars[s].second, rs[k].scalars[s].second))
          << "snapshot " << k << " " << rs[k].scalars[s].first;
  }
  const auto a = ref.find(ref_id), b = got.find(id);
  ASSERT_TRUE(a && b);
  EXPECT_EQ(b->state, "SUCCEEDED") << b->reason;
  const json ja = json::parse(a->summary_json), jb = json::parse(b->summary_json);
  EXPECT_EQ(jb["summary"], ja["summary"]);
  EXPECT_EQ(jb["accuracy"], ja["accuracy"]);
}

// The run of `args` never stopped, made once per kind: its database and job id.
const std::pair<std::string, std::string>& reference(const Args& args) {
  static std::map<std::string, std::pair<std::string, std::string>> runs;
  auto it = runs.find(args.front());
  if (it == runs.end()) {
    const fs::path dir = fresh_dir("resume-reference-" + args.front());
    const std::string db = (dir / "results.db").string();
    it = runs.emplace(args.front(), std::pair{db, run_to_end(dir, args, db)}).first;
  }
  return it->second;
}

// Stops a run of `args` with `sig` once it has checkpointed, resumes it (by an id prefix) and
// compares it with a run that was never stopped.
void stop_resume_and_compare(const std::string& name, const Args& args, int sig,
                             std::size_t frames) {
  clear_mdem_env();
  const fs::path dir = fresh_dir(name);
  const auto& [ref_db, ref_id] = reference(args);
  const std::string db = (dir / "results.db").string();
  const auto [pid, id] = start_until_checkpoint(dir, args, db, frames);
  ASSERT_GT(pid, 0);
  const int code = stop(pid, sig);
  const std::string ls_state = sig == SIGKILL ? "INTERRUPTED" : "CANCELLED";
  EXPECT_EQ(code, sig == SIGKILL ? -1 : mdem::cli::kJobFailed) << slurp(dir / "run.err");
  {
    const ResultsStore store(db);
    const auto rec = store.find(id);
    ASSERT_TRUE(rec.has_value());
    ASSERT_EQ(rec->state, ls_state) << rec->reason;
    if (sig != SIGKILL) {  // the run says how to go on
      EXPECT_TRUE(contains(rec->reason, "mdem run --resume " + id)) << rec->reason;
      EXPECT_TRUE(
          contains(slurp(dir / "run.out") + slurp(dir / "run.err"), "mdem run --resume " + id));
    }
    EXPECT_LT(store.frame_count(id), ResultsStore(ref_db).frame_count(ref_id));
  }
  ASSERT_EQ(DaemonProcess::run({MDEM_CLI_PATH, "ls", "--db", db}, dir / "ls.out"), 0);
  EXPECT_TRUE(contains(slurp(dir / "ls.out"), ls_state)) << slurp(dir / "ls.out");
  const std::string log_before = slurp(dir / "logs" / (id + ".log"));
  ASSERT_FALSE(log_before.empty());

  const auto r = resume(dir, {id.substr(0, id.size() - 2), "--db", db});
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_TRUE(contains(r.err, "resumed at")) << r.err;
  expect_same_results(ref_db, ref_id, db, id);
  // The log goes on after what it held, with where the run resumed.
  const std::string log = slurp(dir / "logs" / (id + ".log"));
  EXPECT_EQ(log.substr(0, log_before.size()), log_before);
  EXPECT_TRUE(contains(log.substr(log_before.size()), "from its checkpoint at step")) << log;
  EXPECT_TRUE(contains(log.substr(log_before.size()), "SUCCEEDED")) << log;
  // Done: no checkpoint is left, and the job is not resumed twice.
  EXPECT_FALSE(fs::exists(dir / "checkpoints" / (id + ".ckpt")));
  const auto again = resume(dir, {id, "--db", db});
  EXPECT_EQ(again.code, mdem::cli::kUsage);
  EXPECT_TRUE(contains(again.err, "has finished (SUCCEEDED)")) << again.err;
}

TEST(CliResume, TwistStoppedByCtrlCResumesToTheSameResults) {
  stop_resume_and_compare("resume-twist-int", kTwist, SIGINT, 5);
}

TEST(CliResume, TwistKilledOutrightResumesToTheSameResults) {
  stop_resume_and_compare("resume-twist-kill", kTwist, SIGKILL, 12);
}

TEST(CliResume, TensileStoppedByCtrlCResumesToTheSameResults) {
  stop_resume_and_compare("resume-tensile-int", kTensile, SIGINT, 3);
}

TEST(CliResume, TensileKilledOutrightResumesToTheSameResults) {
  stop_resume_and_compare("resume-tensile-kill", kTensile, SIGKILL, 8);
}

// ---- refusals ---------------------------------------------------------------------------------

// A twist job stopped by SIGINT with its checkpoint: the subject of the refusals below.
class CliResumeRefusal : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    clear_mdem_env();
    dir_ = new fs::path(fresh_dir("resume-refusals"));
    db_ = new std::string((*dir_ / "results.db").string());
    const auto [pid, id] = start_until_checkpoint(*dir_, kTwistLong, *db_, 3);
    ASSERT_GT(pid, 0);
    EXPECT_EQ(stop(pid, SIGINT), mdem::cli::kJobFailed);
    id_ = new std::string(id);
    ckpt_ = new fs::path(*dir_ / "checkpoints" / (id + ".ckpt"));
    ASSERT_TRUE(fs::exists(*ckpt_));
    original_ = new mdem::CheckpointData(mdem::read_checkpoint(ckpt_->string()));
    frames_ = ResultsStore(*db_).frame_count(id);
  }
  static void TearDownTestSuite() {
    delete dir_;
    delete db_;
    delete id_;
    delete ckpt_;
    delete original_;
  }
  void TearDown() override {  // the next test starts from the job's own checkpoint
    mdem::write_checkpoint(ckpt_->string(), *original_);
  }

  // `mdem run --resume` is refused (exit 2) with a message holding `part`, and the job is as it
  // was: CANCELLED, its frames kept.
  static void expect_refused(const std::string& part, Args args = {}) {
    if (args.empty()) args = {*id_, "--db", *db_};
    const auto r = resume(*dir_, args);
    EXPECT_EQ(r.code, mdem::cli::kUsage) << r.out << r.err;
    EXPECT_TRUE(contains(r.err, part)) << r.err;
    EXPECT_FALSE(contains(r.err, "resumed at")) << r.err;
    const ResultsStore store(*db_);
    EXPECT_EQ(store.find(*id_)->state, "CANCELLED");
    EXPECT_EQ(store.frame_count(*id_), frames_);
  }
  // The checkpoint with its record changed by `edit` (a valid envelope: CRCs match).
  template <class F>
  static void write_record(F edit) {
    mdem::CheckpointData d = *original_;
    json r = json::parse(d.record);
    edit(r);
    d.record = r.dump();
    mdem::write_checkpoint(ckpt_->string(), d);
  }
  // The checkpoint with the engine state's bytes changed by `edit` (CRCs match).
  template <class F>
  static void write_state(F edit) {
    mdem::CheckpointData d = *original_;
    edit(d.state);
    mdem::write_checkpoint(ckpt_->string(), d);
  }
  // The checkpoint with the job's state changed by `edit` after loading it: saved by the
  // engine, so the bytes are consistent (the CRCs and the format too) but for the value changed.
  template <class F>
  static void write_edited_state(F edit) {
    const auto rec = ResultsStore(*db_).find(*id_);
    const auto job =
        mdem::make_spec_job(mdem::spec::finalize(mdem::spec::parse_json(rec->spec_json)),
                            json::parse(original_->record)["threads"].get<int>());
    mdem::load_checkpoint(*job, original_->state);
    edit(job->system());
    mdem::CheckpointData d = *original_;
    d.state = mdem::save_checkpoint(*job);
    mdem::write_checkpoint(ckpt_->string(), d);
  }

  static fs::path* dir_;
  static std::string* db_;
  static std::string* id_;
  static fs::path* ckpt_;
  static mdem::CheckpointData* original_;
  static std::size_t frames_;
};
fs::path* CliResumeRefusal::dir_ = nullptr;
std::string* CliResumeRefusal::db_ = nullptr;
std::string* CliResumeRefusal::id_ = nullptr;
fs::path* CliResumeRefusal::ckpt_ = nullptr;
mdem::CheckpointData* CliResumeRefusal::original_ = nullptr;
std::size_t CliResumeRefusal::frames_ = 0;

TEST_F(CliResumeRefusal, UnknownIdMissingIdOrDatabase) {
  expect_refused("no job 'j-nonesuch'", {"j-nonesuch", "--db", *db_});
  const auto none = resume(*dir_, {"--db", *db_});
  EXPECT_EQ(none.code, mdem::cli::kUsage);
  EXPECT_TRUE(contains(none.err, "ID")) << none.err;
  const auto no_db = resume(*dir_, {*id_, "--db", (*dir_ / "nonesuch.db").string()});
  EXPECT_EQ(no_db.code, mdem::cli::kUsage);
  EXPECT_TRUE(contains(no_db.err, "no results database")) << no_db.err;
  EXPECT_FALSE(fs::exists(*dir_ / "nonesuch.db"));
  expect_refused("--checkpoint-every", {*id_, "--db", *db_, "--checkpoint-every", "nan"});
  expect_refused("--checkpoint-every", {*id_, "--db", *db_, "--checkpoint-every", "1e300"});
}

TEST_F(CliResumeRefusal, MissingTruncatedOrDamagedCheckpoint) {
  fs::remove(*ckpt_);
  expect_refused("has no checkpoint");
  {
    const std::string bytes = [] {
      mdem::write_checkpoint(ckpt_->string(), *original_);
      return slurp(*ckpt_);
    }();
    std::ofstream(*ckpt_, std::ios::binary) << bytes.substr(0, bytes.size() / 2);
  }
  expect_refused("truncated");
  {
    mdem::write_checkpoint(ckpt_->string(), *original_);
    std::fstream f(*ckpt_, std::ios::in | std::ios::out | std::ios::binary);
    f.seekp(200);
    f.write("garbage!", 8);
  }
  expect_refused("CRC-32 mismatch");
  std::ofstream(*ckpt_) << "not a checkpoint at all, but long enough to hold a header";
  expect_refused("not an mdem checkpoint");
  // A daemon's checkpoint: the state alone, no record of what was stored.
  mdem::write_checkpoint(ckpt_->string(), {original_->step, original_->state, {}});
  expect_refused("no record of the results stored");
}

TEST_F(CliResumeRefusal, CheckpointOfAnotherJobKindOrSpec) {
  write_record([](json& r) { r["job_id"] = "j-20260101-000000-0000"; });
  expect_refused("checkpoint of job 'j-20260101-000000-0000'");
  write_record([](json& r) { r["kind"] = "tensile"; });
  expect_refused("checkpoint of a 'tensile' job");
  // The spec with one number of its twist changed: the refusal names that field.
  std::string field;
  write_record([&](json& r) {
    json spec = json::parse(r["spec"].get<std::string>());
    json& twist = spec["twist"];
    for (auto it = twist.begin(); it != twist.end() && field.empty(); ++it)
      if (it.value().is_number_float()) {
        it.value() = it.value().get<double>() * 2 + 1;
        field = "twist." + it.key();
      }
    r["spec"] = spec.dump();
  });
  ASSERT_FALSE(field.empty());
  expect_refused("another spec than job '" + *id_ + "' has (they differ in '" + field + "')");
}

TEST_F(CliResumeRefusal, RecordValuesOutOfRangeOrNotNumbers) {
  write_record([](json& r) { r["frames"] = 1e15; });
  expect_refused("'frames'");
  write_record([](json& r) { r["frames"] = -1; });
  expect_refused("'frames' is -1");
  write_record([](json& r) { r["threads"] = 0; });
  expect_refused("'threads' is 0");
  write_record([](json& r) { r["wall_s"] = 1e300; });
  expect_refused("'wall_s'");
  write_record([](json& r) { r["wall_s"] = "NaN"; });
  expect_refused("'wall_s'");
  write_record([](json& r) { r.erase("last_frame_order"); });
  expect_refused("no 'last_frame_order'");
  // More frames than the database holds: rows the checkpoint counted are gone.
  write_record([](json& r) { r["frames"] = r["frames"].get<long>() + 1000; });
  expect_refused("fewer than the");
}

TEST_F(CliResumeRefusal, EngineStateOfAnotherFormatOrWithNonFiniteOrHugeValues) {
  // The engine's format version (after its 8-byte magic): a build that cannot read it says so.
  write_state([](std::string& s) {
    const std::uint32_t v = 999;
    std::memcpy(s.data() + 8, &v, 4);
  });
  expect_refused("format version 999");
  // A position not finite; a velocity or spin that would fly or turn an element out of its
  // place in one step (no stable run reaches one).
  write_edited_state(
      [](mdem::System& sys) { sys.elements().x[3].x() = std::numeric_limits<double>::infinity(); });
  expect_refused("is not finite of element 3");
  write_edited_state([](mdem::System& sys) {
    sys.elements().v[2].y() = std::numeric_limits<double>::quiet_NaN();
  });
  expect_refused("field 'v': is not finite of element 2");
  write_edited_state([](mdem::System& sys) { sys.elements().v[2].z() = 1e6; });
  expect_refused("more than its radius");
  write_edited_state([](mdem::System& sys) { sys.elements().w[1].x() = 1e9; });
  expect_refused("more than a radian");
  // Saved again unedited, the state is the checkpoint's byte for byte: what was refused above is
  // the value edited, nothing else.
  write_edited_state([](mdem::System&) {});
  EXPECT_EQ(mdem::read_checkpoint(ckpt_->string()).state, original_->state);
}

TEST_F(CliResumeRefusal, FinishedOrDaemonJobs) {
  // A job that ran to its end has nothing to resume.
  const fs::path dir = fresh_dir("resume-finished");
  const std::string db = (dir / "results.db").string();
  const Args short_twist = {"twist", "--layers", "2", "--length",  "8", "--torque",
                            "1",     "--hold",   "1", "--threads", "1"};
  const std::string id = run_to_end(dir, short_twist, db);
  const auto r = resume(dir, {id, "--db", db});
  EXPECT_EQ(r.code, mdem::cli::kUsage);
  EXPECT_TRUE(contains(r.err, "has finished (SUCCEEDED)")) << r.err;
  EXPECT_FALSE(fs::exists(dir / "checkpoints" / (id + ".ckpt")));
}

}  // namespace
