#pragma once
// Job specs (proto/mdem/v1/job.proto): loading from JSON/YAML through Protobuf's JSON mapping,
// defaults and validation. Independent of the engine; the engine never sees protobuf.
//
// Typical use: finalize(load_file(path)) -> a spec with every default filled in and every value
// checked, or a SpecError that lists each bad field with its allowed range.
#include <cstddef>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "mdem/v1/job.pb.h"

namespace mdem::spec {

// One problem with a spec. field: the dotted proto path ("twist.torque_nn_nm",
// "twist.line_defects[1].width", "run.dt_ps"), "kind" for a missing job kind, or "json", "yaml",
// "file" for input that could not be read or parsed.
struct FieldError {
  std::string field;
  std::string message;
};

// Thrown by finalize and the parsers. what(): every error, one per line, "field: message".
class SpecError : public std::invalid_argument {
 public:
  explicit SpecError(std::vector<FieldError> errors);
  const std::vector<FieldError>& errors() const { return errors_; }

 private:
  std::vector<FieldError> errors_;
};

// Largest spec text accepted by parse_json, parse_yaml and load_file.
inline constexpr std::size_t kMaxSpecBytes = std::size_t{16} << 20;

// Fills every unset optional field (run, outputs, the job kind's spec and each twist line defect)
// with its default; boundary UNSPECIFIED becomes CONSTANT_MOMENT. run.dt_ps and twist.spacing_nm
// stay unset: they mean "automatic". A compression spec gets its material's E, nu, density,
// bond kind and strength (material UNSPECIFIED = GOLD); CUSTOM gets none of them (validation
// then asks for E, nu and density, and for the strength of a PLASTIC or BRITTLE bond).
void apply_defaults(mdem::v1::JobSpec& spec);

// Every problem of the spec, not just the first; empty if valid. Unset fields count as their
// defaults, so this works before or after apply_defaults.
std::vector<FieldError> validate(const mdem::v1::JobSpec& spec);

// apply_defaults, then validate; throws SpecError listing all errors.
mdem::v1::JobSpec finalize(mdem::v1::JobSpec spec);

// Protobuf JSON mapping, read as written first: an unknown field, a field given twice (at any
// depth, in either spelling), a value of the wrong kind, a number out of its type's range, a null
// in a list or nesting deeper than 32 is refused. Throws SpecError (field "json") whose message
// names the field path the user wrote, its line:column and what is allowed. Does not apply
// defaults.
mdem::v1::JobSpec parse_json(std::string_view text);

// YAML -> JSON text -> the JSON mapping. Plain scalars: null/~ -> null, true/false -> bool,
// numbers -> numbers, .nan/.inf/-.inf -> "NaN"/"Infinity"/"-Infinity", anything else (and every
// scalar of a string field, so `name: 2024` is a name) -> string; quoted scalars stay strings.
// Throws SpecError (field "yaml") with line and column for a syntax error or a document that is
// not one mapping, and for everything parse_json refuses (located in the YAML text). Does not
// apply defaults.
mdem::v1::JobSpec parse_yaml(std::string_view text);

// Reads a .json, .yaml or .yml file (by extension, case-insensitive) and parses it. Throws
// SpecError (field "file") naming the path for a missing, unreadable or non-regular file, another
// extension, or a file over kMaxSpecBytes. Does not apply defaults.
mdem::v1::JobSpec load_file(const std::string& path);

// JSON with the proto field names; every set field is printed, including zeros and false.
std::string to_json(const mdem::v1::JobSpec& spec, bool pretty);

// round(length_nm / 1.356) with the default length when unset; at least 1.
int twist_segments(const mdem::v1::TwistSpec& twist);

// 3N^2 - 3N + 1 tubes of N hexagon layers (0 for N < 1).
int hex_tube_count(int layers);

// Most grains a compression particle may hold; validate refuses a larger estimate.
inline constexpr double kMaxCompressionGrains = 2'000'000;

// The compression particle's grain count, (1 - porosity) x shell volume / mean grain volume
// with radii uniform in [min, max] (mean r^3 = (a + b)(a^2 + b^2)/4), the defaults standing in
// for unset fields; not rounded. NaN when a field is not finite.
double compression_grain_estimate(const mdem::v1::CompressionSpec& c);

// ---- tensile (mdem.v1.TensileSpec) ----

// Table 5-1's film of a size: side (= width), tubes and segments per tube; every size is 11 nm
// thick. FILM_SIZE_UNSPECIFIED (and a number that names no size) is the small film.
struct FilmPreset {
  double side_nm;
  int tubes;
  int segments_per_tube;
};
FilmPreset film_preset(mdem::v1::FilmSize size);

// Most elements (segments and NPs) a tensile film may hold; validate refuses more.
inline constexpr double kMaxTensileElements = 2'000'000;
// The smallest NP–NP centre distance the film's NP placement accepts: 2 r_NP + the NP–NP law's
// rest gap, 5.4287267 nm (tensile.md §1.2, §3.2).
inline constexpr double kNpMinSpacingNm = 5.4287267;

// The film's element count, tubes x segments_per_tube + nanoparticles, with the size's values
// standing in for unset fields; not rounded. NaN when a field is not finite.
double tensile_element_count(const mdem::v1::TensileSpec& t);
// The most NPs that can fit a side x side x thickness film whatever its tubes: balls of diameter
// kNpMinSpacingNm about the centres, in the slab widened by half of it on every side,
// 6 (side + s)^2 (thickness + s) / (pi s^3) (the engine's placement refuses more at once).
double tensile_np_capacity(double side_nm, double thickness_nm);
// The loading time of the tensile spec's test in ps, its defaults standing in for unset fields:
// monotonic, ramp/2 + target/rate (when the target lies past the ramp's 1/2 rate x ramp; else
// the time on the ramp); cyclic, cycles x 2 amplitude / rate. NaN for a non-finite field.
double tensile_loading_ps(const mdem::v1::TensileSpec& t);

}  // namespace mdem::spec
