#include "mdem/io/state_io.h"

namespace mdem {

namespace {

// Precedes every section name, so a reader that lost step with the writer finds garbage where it
// expects a marker and says so, instead of reading on.
constexpr std::uint32_t kSectionMarker = 0x5EC7109Eu;
constexpr char kMagic[8] = {'M', 'D', 'E', 'M', 'C', 'K', 'P', 'T'};
// Reads back as another value on a machine of the other byte order.
constexpr std::uint32_t kByteOrderProbe = 0x01020304u;

// Type sizes the raw values depend on, packed into one word: long, size_t, double, Vec3, Quat.
std::uint32_t type_sizes() {
  return static_cast<std::uint32_t>(sizeof(long) | sizeof(std::size_t) << 6 | sizeof(double) << 12 |
                                    sizeof(Eigen::Vector3d) << 18 |
                                    sizeof(Eigen::Quaterniond) << 24);
}

}  // namespace

void StateWriter::begin(std::string_view tag) {
  put(kSectionMarker);
  put_string(tag);
}

void StateWriter::put_string(std::string_view s) {
  put(static_cast<std::uint64_t>(s.size()));
  append(s.data(), s.size());
}

void StateReader::fail(std::string_view field, const std::string& what) const {
  std::string m = "checkpoint section '" + section_ + "'";
  if (!field.empty()) m += ", field '" + std::string(field) + "'";
  throw CheckpointError(m + ": " + what);
}

void StateReader::read(void* dst, std::size_t n, std::string_view field) {
  if (n > remaining())
    fail(field, "needs " + std::to_string(n) + " bytes at byte " + std::to_string(pos_) +
                    " but only " + std::to_string(remaining()) +
                    " remain (the checkpoint is truncated)");
  std::memcpy(dst, in_.data() + pos_, n);
  pos_ += n;
}

std::size_t StateReader::count(std::string_view field, std::size_t entry_bytes) {
  const auto n = get<std::uint64_t>(field);
  // Compared as a division: n × entry_bytes may overflow for a corrupt n.
  if (n > remaining() / entry_bytes)
    fail(field, "claims " + std::to_string(n) + " entries of " + std::to_string(entry_bytes) +
                    " bytes but only " + std::to_string(remaining()) +
                    " bytes remain (the checkpoint is truncated or corrupt)");
  return static_cast<std::size_t>(n);
}

void StateReader::begin(std::string_view tag) {
  const std::string expected(tag);
  const std::size_t at = pos_;
  if (get<std::uint32_t>("section marker before '" + expected + "'") != kSectionMarker)
    fail({}, "expected section '" + expected + "' at byte " + std::to_string(at) +
                 " but found no section marker (the checkpoint is corrupt or of another format)");
  const std::string found = get_string("name of section '" + expected + "'");
  if (found != tag)
    fail({}, "expected section '" + expected + "' at byte " + std::to_string(at) + ", found '" +
                 found + "' (the checkpoint is of another scene or format)");
  section_ = expected;
}

bool StateReader::get_bool(std::string_view field) {
  const auto b = get<std::uint8_t>(field);
  if (b > 1) fail(field, "is not a boolean (byte " + std::to_string(b) + ")");
  return b == 1;
}

std::string StateReader::get_string(std::string_view field) {
  std::string s(count(field, 1), '\0');
  if (!s.empty()) read(s.data(), s.size(), field);
  return s;
}

void StateReader::expect_end() const {
  if (remaining() != 0)
    fail({}, std::to_string(remaining()) + " unread bytes after the end of the state (the " +
                 "checkpoint was written by another format or scene)");
}

void write_header(StateWriter& w) {
  for (char c : kMagic) w.put(c);
  w.put(kCheckpointVersion);
  w.put(kByteOrderProbe);
  w.put(type_sizes());
}

void read_header(StateReader& r) {
  char magic[sizeof(kMagic)];
  for (char& c : magic) c = r.get<char>("magic");
  if (std::memcmp(magic, kMagic, sizeof(kMagic)) != 0)
    r.fail("magic", "not an mdem checkpoint (bad magic number)");
  const auto version = r.get<std::uint32_t>("version");
  if (version != kCheckpointVersion)
    r.fail("version", "format version " + std::to_string(version) + ", this build reads version " +
                          std::to_string(kCheckpointVersion));
  if (r.get<std::uint32_t>("byte order") != kByteOrderProbe)
    r.fail("byte order", "written on a machine of another byte order");
  if (r.get<std::uint32_t>("type sizes") != type_sizes())
    r.fail("type sizes", "written by a build with other type sizes");
}

}  // namespace mdem
