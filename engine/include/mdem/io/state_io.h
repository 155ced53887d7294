#pragma once
// Binary checkpoints of a job's full state, so a run can stop at a step boundary and a freshly
// built job (same spec, same thread count) can continue it bit-identically.
//
// The format is a header (magic, version, byte-order and type-size probe) followed by named
// sections of raw values in native byte order: a checkpoint resumes on the machine and build
// that wrote it, it is not an archive format. It has no checksum (a caller storing the bytes
// wraps them in its own); instead the reader checks every length against the bytes left, so
// corrupt input throws CheckpointError and never reads out of bounds or allocates absurd sizes.
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <cstring>
#include <stdexcept>
#include <string>
#include <string_view>
#include <type_traits>
#include <vector>

namespace mdem {

// A checkpoint that cannot be loaded into this job: corrupt or truncated bytes, another format
// version, or the state of a different scene or thread count. The message names the section and
// field where reading stopped.
class CheckpointError : public std::runtime_error {
  using std::runtime_error::runtime_error;
};

namespace state_io_detail {
// Types stored as their raw bytes: trivially copyable ones, plus Eigen's fixed-size vectors and
// quaternions of doubles (plain arrays of doubles, but with user-written copy constructors, so
// not formally trivially copyable).
template <class T>
struct Raw : std::bool_constant<std::is_trivially_copyable_v<T> && !std::is_pointer_v<T> &&
                                !std::is_array_v<T>> {};
template <int R, int C, int O, int MR, int MC>
struct Raw<Eigen::Matrix<double, R, C, O, MR, MC>> : std::bool_constant<(R > 0 && C > 0)> {};
template <int O>
struct Raw<Eigen::Quaternion<double, O>> : std::true_type {};
}  // namespace state_io_detail

template <class T>
concept RawState = state_io_detail::Raw<T>::value;
// Vector entries: std::vector<bool> has no contiguous storage to copy.
template <class T>
concept RawEntry = RawState<T> && !std::is_same_v<T, bool>;

// Appends typed values to a byte string.
class StateWriter {
 public:
  // Starts a named section: the reader checks the name, so a reader out of step with the writer
  // (another format, another scene) stops at the first section and says which.
  void begin(std::string_view tag);

  template <RawState T>
  void put(const T& v) {
    append(&v, sizeof(T));
  }
  void put(bool b) { put(static_cast<std::uint8_t>(b ? 1 : 0)); }
  // Entry count, then the entries' bytes.
  template <RawEntry T>
  void put(const std::vector<T>& v) {
    put(static_cast<std::uint64_t>(v.size()));
    append(v.data(), v.size() * sizeof(T));
  }
  void put_string(std::string_view s);

  const std::string& bytes() const { return out_; }
  std::string take() { return std::move(out_); }
  std::size_t size() const { return out_.size(); }

 private:
  void append(const void* p, std::size_t n) { out_.append(static_cast<const char*>(p), n); }
  std::string out_;
};

// Reads what a StateWriter wrote, in the same order. Every read names its field, and errors say
// "section 'system', field 'x': ...".
class StateReader {
 public:
  explicit StateReader(std::string_view bytes) : in_(bytes) {}

  // Expects the section marker `tag` next.
  void begin(std::string_view tag);

  template <RawState T>
  T get(std::string_view field) {
    T v;
    read(&v, sizeof(T), field);
    return v;
  }
  bool get_bool(std::string_view field);
  // A vector of exactly `expected` entries.
  template <RawEntry T>
  void get(std::vector<T>& v, std::string_view field, std::size_t expected) {
    const std::size_t n = count(field, sizeof(T));
    if (n != expected)
      fail(field,
           "holds " + std::to_string(n) + " entries, this job has " + std::to_string(expected));
    read_vector(v, n, field);
  }
  // A vector of any length the remaining bytes can hold.
  template <RawEntry T>
  void get(std::vector<T>& v, std::string_view field) {
    read_vector(v, count(field, sizeof(T)), field);
  }
  std::string get_string(std::string_view field);

  std::size_t position() const { return pos_; }
  std::size_t remaining() const { return in_.size() - pos_; }
  const std::string& section() const { return section_; }
  // Throws unless every byte was read (trailing bytes mean reader and writer disagree).
  void expect_end() const;
  // Throws CheckpointError naming the current section and the field.
  [[noreturn]] void fail(std::string_view field, const std::string& what) const;

 private:
  void read(void* dst, std::size_t n, std::string_view field);
  // Reads an entry count and checks that count × entry bytes fit in what is left.
  std::size_t count(std::string_view field, std::size_t entry_bytes);
  template <class T>
  void read_vector(std::vector<T>& v, std::size_t n, std::string_view field) {
    v.resize(n);
    if (n) read(v.data(), n * sizeof(T), field);
  }

  std::string_view in_;
  std::size_t pos_ = 0;
  std::string section_ = "header";
};

// Format version of everything written after the header; bump it when any save_state changes.
// 2: staged jobs (the stage index, finished stages' results, then the current stage's state).
// 3: element tags (checked against the job's, like the other element properties).
// 4: the energy ledger's nanoparticle term split into NP–CNT and NP–NP (one more stored term).
// 5: the elements' topology (bonds, tube chains, rings) and groups, loaded in place of the job's.
// 6: multiple time stepping: respa_k, and the slow models' energy held between outer steps.
// 7: element arrays in tag order (tags first), then their memory order (memory_order.h).
// 8: the twist protocol's grip hold (positions, or positions and spins).
// 9: the over-twist check's books (per-tube work of the grip loads and kinetic energy, their
// window).
// 10: the tensile test's pieces held by both grips (count and affine modulus, at its start).
// 11: the tensile job's step check (its step, given or picked, the bound, the measured step).
inline constexpr std::uint32_t kCheckpointVersion = 11;

// A part of a job that a run changes and a checkpoint must carry (a protocol, an observer, a
// stage): it writes and reads its own state, so no job lists fields in a checkpoint by hand.
// load_state reads exactly what save_state wrote, and throws CheckpointError (via
// StateReader::fail) when the bytes belong to another part or another spec.
class Stateful {
 public:
  virtual ~Stateful() = default;
  virtual void save_state(StateWriter& w) const = 0;
  virtual void load_state(StateReader& r) = 0;
};

// Magic "MDEMCKPT", version, and a probe of byte order and type sizes.
void write_header(StateWriter& w);
// Throws CheckpointError for another magic, version, byte order or type sizes.
void read_header(StateReader& r);

}  // namespace mdem
