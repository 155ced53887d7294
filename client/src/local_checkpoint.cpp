#include "local_checkpoint.h"

#include <cmath>
#include <ctime>
#include <nlohmann/json.hpp>
#include <sstream>
#include <system_error>
#include <utility>

#include "mdem/event_order.h"
#include "mdem/io/state_io.h"
#include "results_store.h"

namespace mdem::cli {
namespace {

namespace fs = std::filesystem;
using plain_json = nlohmann::json;  // key order does not matter

// Bounds of the record's numbers: a tampered or damaged record is refused, not trusted.
constexpr long kMaxCount = 1'000'000'000'000L;  // frames, snapshots, steps
constexpr double kMaxWallSeconds = 1e9;         // ~32 years
constexpr int kMaxThreads = 4096;
constexpr long kMaxOrder = event_order(4096, 0);  // far more stages than any job has

[[noreturn]] void refuse(const fs::path& path, const std::string& what) {
  throw ResumeError("checkpoint '" + path.string() + "': " + what);
}

long whole(const fs::path& path, const plain_json& j, const char* key, long lo, long hi) {
  const auto it = j.find(key);
  if (it == j.end()) refuse(path, std::string("its record has no '") + key + "'");
  if (!it->is_number_integer())
    refuse(path, std::string("its record's '") + key + "' is not a whole number: " + it->dump());
  const long v = it->get<long>();
  if (v < lo || v > hi)
    refuse(path, std::string("its record's '") + key + "' is " + std::to_string(v) +
                     " (allowed: " + std::to_string(lo) + ".." + std::to_string(hi) + ")");
  return v;
}

std::string text(const fs::path& path, const plain_json& j, const char* key) {
  const auto it = j.find(key);
  if (it == j.end() || !it->is_string())
    refuse(path, std::string("its record has no text '") + key + "'");
  return it->get<std::string>();
}

// The first place where two JSON documents differ, as a field path ("twist.torque_nNnm").
std::string first_difference(const plain_json& a, const plain_json& b, const std::string& at) {
  if (a.is_object() && b.is_object()) {
    for (const auto& [k, v] : a.items()) {
      const std::string here = at.empty() ? k : at + "." + k;
      if (!b.contains(k)) return here;
      if (const std::string d = first_difference(v, b.at(k), here); !d.empty()) return d;
    }
    for (const auto& [k, v] : b.items())
      if (!a.contains(k)) return at.empty() ? k : at + "." + k;
    return "";
  }
  return a == b ? "" : (at.empty() ? "(the whole spec)" : at);
}

// Now, in the timestamp style of the results database.
std::string utc_timestamp() {
  const std::time_t t = std::time(nullptr);
  std::tm tm{};
  gmtime_r(&t, &tm);
  char buf[32];
  std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%SZ", &tm);
  return buf;
}

}  // namespace

fs::path local_checkpoint_path(const std::string& db, const std::string& id) {
  return fs::absolute(fs::path(db)).parent_path() / "checkpoints" / (id + ".ckpt");
}

void write_local_checkpoint(const fs::path& path, const Job& job, const LocalCheckpointRecord& r) {
  std::error_code ec;
  fs::create_directories(path.parent_path(), ec);
  if (ec)
    throw CheckpointFileError("checkpoint directory '" + path.parent_path().string() +
                              "': cannot create it: " + ec.message());
  const plain_json record = {{"format", "mdem run"},
                             {"job_id", r.job_id},
                             {"kind", r.kind},
                             {"spec", r.spec_json},
                             {"threads", r.threads},
                             {"step", r.step},
                             {"frames", r.frames},
                             {"snapshots", r.snapshots},
                             {"last_frame_order", r.last_frame_order},
                             {"last_snapshot_order", r.last_snapshot_order},
                             {"wall_s", r.wall_s},
                             {"log", r.log}};
  write_checkpoint(path.string(), {r.step, save_checkpoint(job), record.dump()});
}

LocalCheckpoint read_local_checkpoint(const fs::path& path, const std::string& id,
                                      const std::string& kind, const std::string& spec_json) {
  LocalCheckpoint c;
  std::error_code ec;
  if (!fs::exists(path, ec))
    throw ResumeError("job '" + id + "' has no checkpoint: '" + path.string() +
                      "' does not exist (the run had --no-checkpoint, or stopped before its first "
                      "checkpoint, or the file was removed); run its spec again instead (`mdem "
                      "show " +
                      id + " --json` prints it)");
  try {
    c.data = read_checkpoint(path.string());
  } catch (const CheckpointFileError& e) {
    throw ResumeError(e.what());
  }
  if (c.data.record.empty())
    refuse(path,
           "it has no record of the results stored (a daemon's checkpoint, not one of "
           "`mdem run`)");
  const plain_json j = plain_json::parse(c.data.record, nullptr, false);
  if (!j.is_object() || j.value("format", "") != "mdem run")
    refuse(path, "its record is not that of an `mdem run` checkpoint");
  LocalCheckpointRecord& r = c.record;
  r.job_id = text(path, j, "job_id");
  r.kind = text(path, j, "kind");
  r.spec_json = text(path, j, "spec");
  r.log = text(path, j, "log");
  if (r.job_id != id)
    refuse(path, "it is the checkpoint of job '" + r.job_id + "', not '" + id + "'");
  if (r.kind != kind)
    refuse(path,
           "it is the checkpoint of a '" + r.kind + "' job, job '" + id + "' is '" + kind + "'");
  const plain_json mine = plain_json::parse(spec_json, nullptr, false);
  const plain_json theirs = plain_json::parse(r.spec_json, nullptr, false);
  if (theirs.is_discarded()) refuse(path, "its record's spec is not JSON");
  if (mine != theirs)
    refuse(path, "it was written for another spec than job '" + id + "' has (they differ in '" +
                     first_difference(mine, theirs, "") + "')");
  r.threads = static_cast<int>(whole(path, j, "threads", 1, kMaxThreads));
  r.step = whole(path, j, "step", 0, kMaxCount);
  r.frames = whole(path, j, "frames", 0, kMaxCount);
  r.snapshots = whole(path, j, "snapshots", 0, kMaxCount);
  r.last_frame_order = whole(path, j, "last_frame_order", -1, kMaxOrder);
  r.last_snapshot_order = whole(path, j, "last_snapshot_order", -1, kMaxOrder);
  const auto wall = j.find("wall_s");
  if (wall == j.end() || !wall->is_number() || !std::isfinite(wall->get<double>()) ||
      wall->get<double>() < 0 || wall->get<double>() > kMaxWallSeconds)
    refuse(path, "its record's 'wall_s' is " + (wall == j.end() ? "missing" : wall->dump()) +
                     " (allowed: 0.." + std::to_string(static_cast<long>(kMaxWallSeconds)) + " s)");
  r.wall_s = wall->get<double>();
  if (c.data.step != r.step)
    refuse(path, "its header's step " + std::to_string(c.data.step) + " and its record's step " +
                     std::to_string(r.step) + " differ");
  return c;
}

void load_local_checkpoint(const fs::path& path, const LocalCheckpoint& c, Job& job) {
  try {
    load_checkpoint(job, c.data.state);
  } catch (const CheckpointError& e) {
    refuse(path, std::string("this build cannot resume from it: ") + e.what());
  }
}

void add_checkpoint_flags(FlagSpec& spec) {
  spec.with_value.push_back("--checkpoint-every");
  spec.switches.push_back("--no-checkpoint");
}

CheckpointPolicy parse_checkpoint_flags(const std::map<std::string, std::string>& given) {
  CheckpointPolicy c;
  c.enabled = !given.count("--no-checkpoint");
  if (const auto it = given.find("--checkpoint-every"); it != given.end()) {
    if (!c.enabled) throw UsageError("--checkpoint-every and --no-checkpoint: give one of them");
    c.every_s = parse_in_range("--checkpoint-every", it->second, 0.01, 86400, "s");
  }
  return c;
}

std::string resume_command(const std::string& id, const std::string& db) {
  std::string cmd = "mdem run --resume " + id;
  if (db != ResultsStore::default_path()) cmd += " --db " + db;
  return cmd;
}

std::string resumed_line(const std::string& kind, const std::string& id,
                         const LocalCheckpointRecord& r, Job& job) {
  std::ostringstream line;
  line << kind << " " << id << ": resumed at " << utc_timestamp() << " from its checkpoint at step "
       << r.step;
  if (const Stage* st = job.current_stage())
    line << " (stage " << job.stage_index() + 1 << "/" << job.stages().size() << " '" << st->name()
         << "', t = " << job.system().time() << " ps)";
  line << "; " << r.frames << " frames and " << r.snapshots << " snapshots kept";
  return line.str();
}

RunCheckpoints::RunCheckpoints(const CheckpointPolicy& policy, fs::path path,
                               LocalCheckpointRecord base, const LocalCheckpointRecord* resumed)
    : policy_(policy), path_(std::move(path)), record_(std::move(base)) {
  if (!resumed) return;
  record_.frames = resumed->frames;
  record_.snapshots = resumed->snapshots;
  record_.last_frame_order = skip_frames_to_ = resumed->last_frame_order;
  record_.last_snapshot_order = skip_snapshots_to_ = resumed->last_snapshot_order;
  wall_before_ = resumed->wall_s;
}

bool RunCheckpoints::take_frame(int stage, long step) {
  const long order = event_order(stage, step);
  if (order <= skip_frames_to_) return false;
  ++record_.frames;
  record_.last_frame_order = order;
  return true;
}

bool RunCheckpoints::take_snapshot(int stage, long step) {
  const long order = event_order(stage, step);
  if (order <= skip_snapshots_to_) return false;
  ++record_.snapshots;
  record_.last_snapshot_order = order;
  return true;
}

bool RunCheckpoints::due(const Job& job) const {
  if (!policy_.enabled) return false;
  if (std::chrono::duration<double>(Clock::now() - last_).count() >= policy_.every_s) return true;
  const Stage* st = job.current_stage();
  return st && st->finished() && job.stage_index() + 1 < job.stages().size();
}

void RunCheckpoints::write(const Job& job) {
  last_ = Clock::now();
  record_.step = job.overall_step();
  record_.wall_s = wall_s();
  write_local_checkpoint(path_, job, record_);
}

double RunCheckpoints::wall_s() const {
  return wall_before_ + std::chrono::duration<double>(Clock::now() - start_).count();
}

void RunCheckpoints::remove() const {
  std::error_code ec;
  fs::remove(path_, ec);
}

}  // namespace mdem::cli
