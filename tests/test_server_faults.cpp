// mdemd's faults (issue 11): nothing acknowledged is lost when the data directory is deleted,
// replaced or stops taking writes (submits are UNAVAILABLE, health NOT_SERVING); a full disk
// never hangs a job (it runs on and its log catches up once space returns); requests with
// fields mdemd cannot read are refused naming them; misleading messages (a bad TLS certificate,
// a checkpoint path that is a directory) name the file; a config file's duplicate keys are
// refused. Full and read-only disks are real small tmpfs mounts where the test may mount one
// (tests run as root), and the daemon's fault-injection hook (MDEMD_FAULT_FILE) otherwise.
#include <google/protobuf/unknown_field_set.h>
#include <grpcpp/generic/generic_stub.h>
#include <gtest/gtest.h>
#include <sys/mount.h>

#include <cstdlib>
#include <cstring>
#include <functional>
#include <future>
#include <nlohmann/json.hpp>

#include "server_support.h"

namespace {

using namespace mdem::testing;
using grpc::health::v1::HealthCheckResponse;

// A tmpfs of `size_mb` mounted at `at` for the test's life (read-only if asked); ok() false
// where mounting is not permitted.
class TmpfsMount {
 public:
  TmpfsMount(const fs::path& at, int size_mb, bool read_only = false) : at_(at) {
    fs::create_directories(at);
    const std::string opts = "size=" + std::to_string(size_mb) + "m";
    ok_ = ::mount("tmpfs", at.c_str(), "tmpfs", read_only ? MS_RDONLY : 0, opts.c_str()) == 0;
  }
  ~TmpfsMount() { unmount(); }
  bool ok() const { return ok_; }
  void unmount() {
    if (ok_) ::umount2(at_.c_str(), MNT_DETACH);
    ok_ = false;
  }

 private:
  fs::path at_;
  bool ok_ = false;
};

// Fills the filesystem holding `dir` with a file until it refuses a byte more.
void fill_disk(const fs::path& file) {
  std::FILE* f = std::fopen(file.c_str(), "wb");
  ASSERT_NE(f, nullptr);
  std::setvbuf(f, nullptr, _IONBF, 0);
  const std::string block(1 << 16, 'x');
  while (std::fwrite(block.data(), 1, block.size(), f) == block.size()) {
  }
  while (std::fwrite("x", 1, 1, f) == 1) {
  }
  std::fclose(f);
}

// While this object lives, the daemons it starts see MDEMD_FAULT_FILE=<dir>/fault; fault(true)
// makes every write to their data directory fail as on a full disk.
class InjectedFault {
 public:
  explicit InjectedFault(const fs::path& dir) : file_(dir / "fault") {
    ::setenv("MDEMD_FAULT_FILE", file_.c_str(), 1);
  }
  ~InjectedFault() { ::unsetenv("MDEMD_FAULT_FILE"); }
  void fault(bool on) {
    if (on)
      std::ofstream(file_) << "on\n";
    else
      fs::remove(file_);
  }

 private:
  fs::path file_;
};

// Polls health until it is `want` (or 5 s pass).
HealthCheckResponse::ServingStatus await_health(const DaemonProcess& d,
                                                HealthCheckResponse::ServingStatus want) {
  HealthCheckResponse::ServingStatus s = health(d);
  for (int i = 0; i < 100 && s != want; ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
    s = health(d);
  }
  return s;
}

// A submit is refused UNAVAILABLE with a reason containing `why`, and health is NOT_SERVING.
void expect_refused(const DaemonProcess& d, const std::string& rid, const std::string& why) {
  const Submitted s = submit(d, kAliceToken, rid, small_spec(5));
  EXPECT_EQ(s.status.error_code(), grpc::StatusCode::UNAVAILABLE) << s.status.error_message();
  EXPECT_NE(s.status.error_message().find(why), std::string::npos) << s.status.error_message();
  EXPECT_EQ(await_health(d, HealthCheckResponse::NOT_SERVING), HealthCheckResponse::NOT_SERVING);
}

TEST(ServerFaults, DeletedDataDirectoryRefusesSubmits) {
  const fs::path dir = fresh_dir("rm-data");
  DaemonProcess d(dir);
  const std::string id = submit_ok(d, kAliceToken, "before", small_spec(5));
  EXPECT_EQ(wait_finished(d, id).state(), mdem::v1::SUCCEEDED);
  fs::remove_all(d.data_dir());
  expect_refused(d, "after", "data directory '" + d.data_dir().string() + "' is gone");
  // Found by the periodic check too, without a submit: a fresh daemon, its directory replaced.
  const fs::path dir2 = fresh_dir("replace-data");
  DaemonProcess d2(dir2);
  EXPECT_EQ(health(d2), HealthCheckResponse::SERVING);
  fs::rename(d2.data_dir(), dir2 / "moved");
  fs::create_directories(d2.data_dir() / "checkpoints");
  EXPECT_EQ(await_health(d2, HealthCheckResponse::NOT_SERVING), HealthCheckResponse::NOT_SERVING);
  expect_refused(d2, "x", "was replaced");
  // A directory replaced by a file.
  const fs::path dir3 = fresh_dir("file-data");
  DaemonProcess d3(dir3);
  fs::remove_all(d3.data_dir());
  std::ofstream(d3.data_dir()) << "not a directory";
  expect_refused(d3, "x", "not a directory");
  EXPECT_NE(d3.log().find("event=storage_fault"), std::string::npos) << d3.log();
}

TEST(ServerFaults, ReplacedDatabaseRefusesSubmits) {
  DaemonProcess d(fresh_dir("replace-db"));
  const fs::path db = d.data_dir() / "jobs.db";
  fs::copy_file(db, d.data_dir() / "copy.db");
  fs::rename(d.data_dir() / "copy.db", db);  // same bytes, another file
  expect_refused(d, "x", "job database '" + db.string() + "' was replaced");
  // After a restart on the new file the daemon serves again (nothing it acknowledged was lost:
  // it acknowledged nothing since).
  d.kill9();
  d.start();
  EXPECT_EQ(health(d), HealthCheckResponse::SERVING);
  EXPECT_TRUE(submit(d, kAliceToken, "again", small_spec(5)).status.ok());
}

// Root ignores permissions, so "unwritable" is a real read-only filesystem: one mounted over
// DATA/checkpoints while the daemon runs (a read-only remount of the data directory itself is
// refused while the database is open for writing).
TEST(ServerFaults, ReadOnlyDataDirectoryRefusesSubmitsUntilWritable) {
  const fs::path dir = fresh_dir("ro-data");
  DaemonProcess d(dir);
  TmpfsMount ro(d.data_dir() / "checkpoints", 1, true);
  if (!ro.ok()) GTEST_SKIP() << "cannot mount a tmpfs here (InjectedWriteFailure covers this)";
  expect_refused(d, "ro", "Read-only file system");
  ro.unmount();
  EXPECT_EQ(await_health(d, HealthCheckResponse::SERVING), HealthCheckResponse::SERVING);
  const std::string id = submit_ok(d, kAliceToken, "rw", small_spec(5));
  EXPECT_EQ(wait_finished(d, id).state(), mdem::v1::SUCCEEDED);
}

// The job's log has every event from 1 with no gap and ends SUCCEEDED, and its frames are those
// of an uninterrupted run of the same spec, step for step and bit for bit: nothing was lost.
void expect_whole_log(const DaemonProcess& d, const std::string& id, const std::string& ref) {
  const auto ev = watch(d, kAliceToken, id, 1);
  expect_contiguous(ev);
  ASSERT_FALSE(ev.empty());
  EXPECT_EQ(ev.back().state().state(), mdem::v1::SUCCEEDED);
  EXPECT_TRUE(of_kind(ev, JobEvent::kCoalesced).empty());
  EXPECT_EQ(of_kind(ev, JobEvent::kReport).size(), 1u);
  const auto frames = frames_by_step(ev),
             ref_frames = frames_by_step(watch(d, kAliceToken, ref, 1));
  ASSERT_EQ(frames.size(), ref_frames.size());
  for (const auto& [step, v] : ref_frames) {
    ASSERT_TRUE(frames.count(step)) << "frame at step " << step << " missing";
    EXPECT_EQ(std::memcmp(v.data(), frames.at(step).data(), v.size() * sizeof(double)), 0)
        << "frame at step " << step << " differs";
  }
}

// A long job is running when the disk fills: submits are UNAVAILABLE, health NOT_SERVING, the job
// RUNNING; once space returns the job finishes with its whole log. `frozen`: the fault stops
// every write, so the job's row must not move meanwhile (on a real disk SQLite may go on in the
// space its write-ahead log already holds).
void full_disk_run(DaemonProcess& d, const std::function<void(bool)>& full, bool frozen) {
  const JobSpec spec = small_spec(300, 5);
  const std::string id = submit_ok(d, kAliceToken, "long", spec);
  wait_for(d, id, [](const JobInfo& j) { return j.step() > 300; });
  full(true);
  expect_refused(d, "while-full", "No space left on device");
  const long step0 = get(d, kRootToken, id).step();
  std::this_thread::sleep_for(std::chrono::milliseconds(1500));
  const JobInfo during = get(d, kRootToken, id);
  EXPECT_EQ(during.state(), mdem::v1::RUNNING);
  if (frozen) {
    EXPECT_EQ(during.step(), step0) << "the database took writes through the fault?";
  }
  full(false);
  EXPECT_EQ(await_health(d, HealthCheckResponse::SERVING), HealthCheckResponse::SERVING);
  const JobInfo done = wait_finished(d, id, 120);
  EXPECT_EQ(done.state(), mdem::v1::SUCCEEDED) << done.reason() << "\n" << d.log();
  const std::string ref = submit_ok(d, kAliceToken, "reference", spec);  // after: uninterrupted
  EXPECT_EQ(wait_finished(d, ref).state(), mdem::v1::SUCCEEDED);
  expect_whole_log(d, id, ref);
  // The fault was met: a checkpoint and a commit of the log failed, and the log caught up.
  EXPECT_NE(d.log().find("event=checkpoint_failed"), std::string::npos) << d.log();
  EXPECT_NE(d.log().find("event=log_recovered"), std::string::npos) << d.log();
}

TEST(ServerFaults, FullDiskNeverHangsAJob) {
  const fs::path dir = fresh_dir("full-disk");
  TmpfsMount m(dir / "data", 24);
  if (!m.ok()) GTEST_SKIP() << "cannot mount a tmpfs here (InjectedWriteFailure covers this)";
  DaemonProcess d(dir, {"--checkpoint-every", "0.2"});
  full_disk_run(
      d,
      [&](bool full) {
        if (full)
          fill_disk(d.data_dir() / "filler");
        else
          fs::remove(d.data_dir() / "filler");
      },
      false);
}

TEST(ServerFaults, InjectedWriteFailureNeverHangsAJob) {
  const fs::path dir = fresh_dir("inject");
  InjectedFault fault(dir);
  DaemonProcess d(dir, {"--checkpoint-every", "0.2"});
  full_disk_run(
      d, [&](bool on) { fault.fault(on); }, true);
}

// SubmitJob with these exact bytes as the request (as a client with another schema would send).
grpc::Status raw_submit(const DaemonProcess& d, const std::string& bytes) {
  grpc::GenericStub stub(d.channel());
  grpc::Slice slice(bytes);
  grpc::ByteBuffer req(&slice, 1), resp;
  auto ctx = ctx_for(kAliceToken, 30);
  std::promise<grpc::Status> done;
  stub.UnaryCall(ctx.get(), "/mdem.v1.JobService/SubmitJob", grpc::StubOptions(), &req, &resp,
                 [&](grpc::Status s) { done.set_value(std::move(s)); });
  return done.get_future().get();
}

long jobs_of_alice(const DaemonProcess& d) {
  mdem::v1::ListJobsRequest req;
  mdem::v1::ListJobsResponse resp;
  auto ctx = ctx_for(kAliceToken);
  EXPECT_TRUE(d.stub()->ListJobs(ctx.get(), req, &resp).ok());
  return resp.jobs_size();
}

// A varint, as the wire format writes lengths and tags.
std::string varint(unsigned long v) {
  std::string out;
  do {
    out.push_back(static_cast<char>((v & 0x7f) | (v > 0x7f ? 0x80 : 0)));
    v >>= 7;
  } while (v > 0);
  return out;
}

TEST(ServerFaults, UnreadableFieldsAreRefusedNamingThem) {
  DaemonProcess d(fresh_dir("wire"));
  mdem::v1::SubmitJobRequest good;
  good.set_request_id("r");
  *good.mutable_spec() = small_spec(5);
  // layers and length_nm sent as bytes: protobuf keeps them as unknown fields and the twist
  // would run with its defaults (91 tubes).
  {
    mdem::v1::SubmitJobRequest req = good;
    auto* twist = req.mutable_spec()->mutable_twist();
    twist->clear_layers();
    twist->clear_length_nm();
    auto* unknown = twist->GetReflection()->MutableUnknownFields(twist);
    unknown->AddLengthDelimited(1, "2");
    unknown->AddLengthDelimited(2, "13.56");
    const grpc::Status s = raw_submit(d, req.SerializeAsString());
    EXPECT_EQ(s.error_code(), grpc::StatusCode::INVALID_ARGUMENT) << s.error_message();
    EXPECT_NE(s.error_message().find("spec.twist: field 1 ('layers', int32) arrived as "
                                     "length-delimited bytes"),
              std::string::npos)
        << s.error_message();
    EXPECT_NE(s.error_message().find("spec.twist: field 2 ('length_nm', double)"),
              std::string::npos)
        << s.error_message();
  }
  // A field the request does not have, at the top and deep inside.
  {
    mdem::v1::SubmitJobRequest req = good;
    req.GetReflection()->MutableUnknownFields(&req)->AddVarint(99, 1);
    auto* outputs = req.mutable_spec()->mutable_outputs();
    outputs->GetReflection()->MutableUnknownFields(outputs)->AddFixed64(77, 5);
    const grpc::Status s = raw_submit(d, req.SerializeAsString());
    EXPECT_EQ(s.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
    EXPECT_NE(s.error_message().find("SubmitJobRequest: field 99 (a varint) is not a field of "
                                     "mdem.v1.SubmitJobRequest"),
              std::string::npos)
        << s.error_message();
    EXPECT_NE(s.error_message().find("spec.outputs: field 77 (a 64-bit value)"), std::string::npos)
        << s.error_message();
  }
  // 100 000 levels of nested unknown messages (bytes to protobuf): refused by the first level.
  {
    std::vector<std::string> heads;  // innermost first: the tag and the length of what it holds
    std::size_t inner = 0;
    for (int level = 0; level < 100000; ++level) {
      heads.push_back(varint((99 << 3) | 2) + varint(inner));
      inner += heads.back().size();
    }
    std::string nested;
    for (auto h = heads.rbegin(); h != heads.rend(); ++h) nested += *h;
    const auto t0 = Clock::now();
    const grpc::Status s = raw_submit(d, good.SerializeAsString() + nested);
    EXPECT_EQ(s.error_code(), grpc::StatusCode::INVALID_ARGUMENT) << s.error_message();
    EXPECT_NE(s.error_message().find("field 99"), std::string::npos);
    EXPECT_LT(std::chrono::duration<double>(Clock::now() - t0).count(), 2.0);
  }
  // 100 000 levels of nested unknown groups: protobuf's parser stops at its nesting limit (100).
  {
    std::string groups;
    for (int level = 0; level < 100000; ++level) groups += varint((99 << 3) | 3);
    for (int level = 0; level < 100000; ++level) groups += varint((99 << 3) | 4);
    const auto t0 = Clock::now();
    const grpc::Status s = raw_submit(d, good.SerializeAsString() + groups);
    EXPECT_EQ(s.error_code(), grpc::StatusCode::INVALID_ARGUMENT) << s.error_message();
    EXPECT_NE(s.error_message().find("deeper than 100 levels"), std::string::npos)
        << s.error_message();
    EXPECT_LT(std::chrono::duration<double>(Clock::now() - t0).count(), 2.0);
  }
  EXPECT_EQ(jobs_of_alice(d), 0);
  // The same request without the extras is taken.
  EXPECT_TRUE(raw_submit(d, good.SerializeAsString()).ok());
  EXPECT_EQ(jobs_of_alice(d), 1);
}

// Starts mdemd with `args` (after the binary); its exit code and log.
std::pair<int, std::string> start_fails(const fs::path& dir, std::vector<std::string> args) {
  args.insert(args.begin(), MDEMD_PATH);
  fs::remove(dir / "start.log");
  const int code = DaemonProcess::run(args, dir / "start.log", dir / "start.log");
  return {code, slurp(dir / "start.log")};
}

TEST(ServerFaults, ConfigFileRefusesDuplicateKeys) {
  const fs::path dir = fresh_dir("config-dup");
  std::ofstream(dir / "cfg.yaml") << "token_file: t\nworkers: 2\ndata_dir: d\nworkers: 3\n";
  const auto [code, log] = start_fails(dir, {"--config", (dir / "cfg.yaml").string()});
  EXPECT_EQ(code, 2);
  EXPECT_NE(log.find("key 'workers' given twice (lines 2 and 4)"), std::string::npos) << log;
}

TEST(ServerFaults, BadTlsCertificateOrKeyIsNamed) {
  const fs::path dir = fresh_dir("bad-tls");
  write_private(dir / "tokens", std::string(kAliceToken) + " alice\n");
  const std::string mk = "openssl req -x509 -newkey rsa:2048 -nodes -days 1 -subj /CN=localhost ";
  ASSERT_EQ(std::system((mk + "-keyout " + (dir / "key.pem").string() + " -out " +
                         (dir / "cert.pem").string() + " >/dev/null 2>&1")
                            .c_str()),
            0);
  ASSERT_EQ(std::system((mk + "-keyout " + (dir / "key2.pem").string() + " -out " +
                         (dir / "cert2.pem").string() + " >/dev/null 2>&1")
                            .c_str()),
            0);
  std::ofstream(dir / "garbage.pem") << "this is no certificate\n";
  std::ofstream(dir / "bad-body.pem")
      << "-----BEGIN CERTIFICATE-----\nbm90IGEgY2VydGlmaWNhdGU=\n-----END CERTIFICATE-----\n";
  auto start = [&](const std::string& cert, const std::string& key) {
    return start_fails(dir, {"--listen", "127.0.0.1:0", "--data-dir", (dir / "data").string(),
                             "--token-file", (dir / "tokens").string(), "--tls-cert",
                             (dir / cert).string(), "--tls-key", (dir / key).string()});
  };
  for (const auto& [cert, key, says] :
       std::vector<std::tuple<std::string, std::string, std::string>>{
           {"garbage.pem", "key.pem",
            "TLS certificate '" + (dir / "garbage.pem").string() +
                "': no '-----BEGIN ...CERTIFICATE-----' block"},
           {"key.pem", "cert.pem", "TLS key '" + (dir / "cert.pem").string() + "': no"},
           {"cert.pem", "missing.pem", "TLS key '" + (dir / "missing.pem").string() + "'"},
           {"bad-body.pem", "key.pem",
            "TLS refused the certificate '" + (dir / "bad-body.pem").string() + "' or the key"},
           {"cert.pem", "key2.pem", "TLS refused the certificate"}}) {
    const auto [code, log] = start(cert, key);
    EXPECT_EQ(code, 1) << log;
    EXPECT_NE(log.find(says), std::string::npos) << cert << " " << key << ":\n" << log;
    EXPECT_EQ(log.find("address in use"), std::string::npos) << log;
  }
}

TEST(ServerFaults, CheckpointPathThatIsADirectoryIsNamed) {
  DaemonProcess d(fresh_dir("ckpt-dir"), {"--checkpoint-every", "0.2"});
  // A job far longer than the wait for its first checkpoint: a 200 ps hold (~0.5 s) could end,
  // and drop its checkpoint, between that wait and the kill (this test failed so once under -j2).
  const std::string id = submit_ok(d, kAliceToken, "victim", small_spec(4000));
  const fs::path ckpt = kill_after_checkpoint(d, id);
  ASSERT_TRUE(fs::exists(ckpt));
  fs::remove(ckpt);
  fs::create_directories(ckpt);
  d.start();
  const JobInfo failed = wait_finished(d, id);
  EXPECT_EQ(failed.state(), mdem::v1::FAILED);
  EXPECT_NE(failed.reason().find("checkpoint '" + ckpt.string() + "': is a directory"),
            std::string::npos)
      << failed.reason();
  EXPECT_EQ(failed.reason().find("basic_filebuf"), std::string::npos) << failed.reason();
}

}  // namespace
