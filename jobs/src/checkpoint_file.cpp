#include "mdem/checkpoint_file.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>
#include <zlib.h>

#include <cerrno>
#include <cstdint>
#include <cstring>
#include <filesystem>

namespace mdem {
namespace {

constexpr char kMagic[8] = {'M', 'D', 'E', 'M', 'C', 'K', 'P', 'T'};
constexpr std::uint32_t kVersion = 1;                    // state only
constexpr std::uint32_t kRecordVersion = 2;              // state and a record
constexpr std::size_t kHeaderBytes = 8 + 4 + 8 + 8 + 4;  // magic, version, step, length, crc
constexpr std::size_t kRecordHeaderBytes = 8 + 4;        // format 2: record length, crc

void put(std::string& out, std::uint64_t v, int bytes) {
  for (int b = 0; b < bytes; ++b) out.push_back(static_cast<char>((v >> (8 * b)) & 0xff));
}

std::uint64_t get(const std::string& in, std::size_t at, int bytes) {
  std::uint64_t v = 0;
  for (int b = 0; b < bytes; ++b)
    v |= static_cast<std::uint64_t>(static_cast<unsigned char>(in[at + b])) << (8 * b);
  return v;
}

std::uint32_t crc_of(const std::string& s) {
  uLong crc = crc32(0L, Z_NULL, 0);
  const auto* p = reinterpret_cast<const Bytef*>(s.data());
  std::size_t left = s.size();
  while (left > 0) {  // crc32 takes a uInt length
    const uInt n = static_cast<uInt>(std::min<std::size_t>(left, 1u << 30));
    crc = crc32(crc, p, n);
    p += n;
    left -= n;
  }
  return static_cast<std::uint32_t>(crc);
}

[[noreturn]] void fail(const std::string& path, const std::string& what) {
  throw CheckpointFileError("checkpoint '" + path + "': " + what);
}

void write_all(int fd, const std::string& bytes, const std::string& path) {
  std::size_t done = 0;
  while (done < bytes.size()) {
    const ssize_t n = ::write(fd, bytes.data() + done, bytes.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) fail(path, std::string("cannot write: ") + std::strerror(errno));
    done += static_cast<std::size_t>(n);
  }
}

}  // namespace

void write_checkpoint(const std::string& path, const CheckpointData& data) {
  const bool with_record = !data.record.empty();
  std::string header(kMagic, 8);
  put(header, with_record ? kRecordVersion : kVersion, 4);
  put(header, static_cast<std::uint64_t>(data.step), 8);
  put(header, data.state.size(), 8);
  put(header, crc_of(data.state), 4);
  if (with_record) {
    put(header, data.record.size(), 8);
    put(header, crc_of(data.record), 4);
  }
  const std::string tmp = path + ".tmp";
  const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0600);
  if (fd < 0) fail(tmp, std::string("cannot create: ") + std::strerror(errno));
  try {
    write_all(fd, header, tmp);
    write_all(fd, data.state, tmp);
    write_all(fd, data.record, tmp);
    if (::fsync(fd) != 0) fail(tmp, std::string("cannot flush: ") + std::strerror(errno));
  } catch (...) {
    ::close(fd);
    ::unlink(tmp.c_str());
    throw;
  }
  ::close(fd);
  if (std::rename(tmp.c_str(), path.c_str()) != 0) {
    const std::string why = std::strerror(errno);
    ::unlink(tmp.c_str());
    fail(path, "cannot replace: " + why);
  }
  // Make the rename itself durable.
  const std::string dir = std::filesystem::path(path).parent_path().string();
  const int dfd = ::open(dir.empty() ? "." : dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (dfd >= 0) {
    ::fsync(dfd);
    ::close(dfd);
  }
}

namespace {

// The whole file; errors name the file and the system's reason (a directory in its place too).
std::string read_all(const std::string& path) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) fail(path, std::string("cannot open: ") + std::strerror(errno));
  struct stat st {};
  if (::fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) {
    ::close(fd);
    fail(path,
         S_ISDIR(st.st_mode) ? "is a directory, not a checkpoint file" : "is not a regular file");
  }
  std::string bytes;
  char buf[1 << 16];
  while (true) {
    const ssize_t n = ::read(fd, buf, sizeof buf);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) {
      const std::string why = std::strerror(errno);
      ::close(fd);
      fail(path, "cannot read: " + why);
    }
    if (n == 0) break;
    bytes.append(buf, static_cast<std::size_t>(n));
  }
  ::close(fd);
  return bytes;
}

}  // namespace

CheckpointData read_checkpoint(const std::string& path) {
  const std::string bytes = read_all(path);
  if (bytes.size() < kHeaderBytes)
    fail(path, "truncated: " + std::to_string(bytes.size()) + " bytes, shorter than its header");
  if (std::memcmp(bytes.data(), kMagic, 8) != 0) fail(path, "not an mdem checkpoint (bad magic)");
  const auto version = static_cast<std::uint32_t>(get(bytes, 8, 4));
  if (version != kVersion && version != kRecordVersion)
    fail(path, "format version " + std::to_string(version) + ", this build reads versions " +
                   std::to_string(kVersion) + " and " + std::to_string(kRecordVersion));
  const std::size_t header = kHeaderBytes + (version == kRecordVersion ? kRecordHeaderBytes : 0);
  if (bytes.size() < header)
    fail(path, "truncated: " + std::to_string(bytes.size()) + " bytes, shorter than its header");
  CheckpointData d;
  d.step = static_cast<long>(get(bytes, 12, 8));
  const std::uint64_t len = get(bytes, 20, 8);
  const auto crc = static_cast<std::uint32_t>(get(bytes, 28, 4));
  const std::uint64_t record_len = version == kRecordVersion ? get(bytes, 32, 8) : 0;
  const auto record_crc =
      version == kRecordVersion ? static_cast<std::uint32_t>(get(bytes, 40, 4)) : crc_of("");
  // Compared without adding: a corrupt length may be near 2^64.
  const std::size_t present = bytes.size() - header;
  if (len > present || record_len != present - len)
    fail(path,
         "truncated or padded: header says " + std::to_string(len) + " bytes of state" +
             (version == kRecordVersion ? " and " + std::to_string(record_len) + " bytes of record"
                                        : std::string()) +
             ", " + std::to_string(present) + " present");
  d.state = bytes.substr(header, len);
  if (crc_of(d.state) != crc) fail(path, "damaged: CRC-32 mismatch");
  d.record = bytes.substr(header + len);
  if (crc_of(d.record) != record_crc) fail(path, "damaged: CRC-32 mismatch of its record");
  return d;
}

}  // namespace mdem
