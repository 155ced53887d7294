// validate(): every problem of a spec, each with its field path and the allowed values.
#include <cmath>
#include <cstdio>
#include <string>

#include "mdem/spec.h"
#include "mdem/spec_kinds.h"

namespace mdem::spec {

namespace {

namespace r = ranges;
using Report = Checks;

// ---- name ----

struct Utf8Scan {
  bool valid = true;
  std::size_t chars = 0;
  long control_at = -1;  // 0-based character index of the first control character
  char32_t control = 0;
};

// Length of the UTF-8 sequence led by byte b, 0 if b cannot lead one.
int utf8_length(unsigned char b) {
  if (b < 0x80) return 1;
  if (b >= 0xC2 && b <= 0xDF) return 2;
  if (b >= 0xE0 && b <= 0xEF) return 3;
  if (b >= 0xF0 && b <= 0xF4) return 4;
  return 0;
}

// Decodes the code point at s[i] of length len; false for a bad continuation, an overlong form,
// a surrogate or a value above U+10FFFF.
bool utf8_decode(std::string_view s, std::size_t i, int len, char32_t& cp) {
  if (i + len > s.size()) return false;
  static constexpr unsigned char kLeadMask[] = {0, 0x7F, 0x1F, 0x0F, 0x07};
  cp = static_cast<unsigned char>(s[i]) & kLeadMask[len];
  for (int k = 1; k < len; ++k) {
    const auto c = static_cast<unsigned char>(s[i + k]);
    if ((c & 0xC0) != 0x80) return false;
    cp = (cp << 6) | (c & 0x3F);
  }
  static constexpr char32_t kMin[] = {0, 0, 0x80, 0x800, 0x10000};
  return cp >= kMin[len] && cp <= 0x10FFFF && !(cp >= 0xD800 && cp <= 0xDFFF);
}

bool is_control(char32_t cp) { return cp < 0x20 || (cp >= 0x7F && cp <= 0x9F); }

Utf8Scan scan_utf8(std::string_view s) {
  Utf8Scan scan;
  for (std::size_t i = 0; i < s.size();) {
    const int len = utf8_length(static_cast<unsigned char>(s[i]));
    char32_t cp = 0;
    if (len == 0 || !utf8_decode(s, i, len, cp)) {
      scan.valid = false;
      return scan;
    }
    if (is_control(cp) && scan.control_at < 0) {
      scan.control_at = static_cast<long>(scan.chars);
      scan.control = cp;
    }
    ++scan.chars;
    i += len;
  }
  return scan;
}

std::string code_point_text(char32_t cp) {
  char buf[16];
  std::snprintf(buf, sizeof buf, "U+%04X", static_cast<unsigned>(cp));
  return buf;
}

void check_name(const mdem::v1::JobSpec& spec, Report& rep) {
  if (!spec.has_name()) return;
  const std::string rule = "(allowed: at most " + std::to_string(r::kNameMaxChars) +
                           " characters of UTF-8 text, no control characters)";
  const Utf8Scan scan = scan_utf8(spec.name());
  if (!scan.valid) return rep.add("name", "is not valid UTF-8 " + rule);
  if (scan.chars > r::kNameMaxChars)
    rep.add("name", std::to_string(scan.chars) + " characters is too long " + rule);
  if (scan.control_at >= 0)
    rep.add("name", "control character " + code_point_text(scan.control) + " at character " +
                        std::to_string(scan.control_at + 1) + " " + rule);
}

// ---- run and outputs ----

void check_run(const mdem::v1::RunSettings& run, Report& rep) {
  rep.real("run.dt_ps", run.has_dt_ps(), run.dt_ps(), r::kDtPs);
  rep.real("run.safety", run.has_safety(), run.safety(), r::kSafety);
  rep.integer("run.threads", run.has_threads(), run.threads(), r::kThreads);
  rep.integer("run.respa_k", run.has_respa_k(), run.respa_k(), r::kRespaK);
}

void check_outputs(const mdem::v1::Outputs& out, Report& rep) {
  rep.real("outputs.energy_every_ps", out.has_energy_every_ps(), out.energy_every_ps(),
           r::kEnergyEveryPs);
  rep.real("outputs.snapshot_every_ps", out.has_snapshot_every_ps(), out.snapshot_every_ps(),
           r::kSnapshotEveryPs);
}

void check_kind(const mdem::v1::JobSpec& spec, const KindRulesRegistry& kinds, Report& rep) {
  const KindRules* kind = kinds.of(spec);
  if (kind) return kind->validate(spec, rep);
  if (spec.kind_case() == mdem::v1::JobSpec::KIND_NOT_SET)
    return rep.add("kind", "no job kind given (allowed: " + kinds.names() + ")");
  rep.add("kind", "job kind " + std::to_string(spec.kind_case()) +
                      " is not one this build knows (allowed: " + kinds.names() + ")");
}

}  // namespace

std::vector<FieldError> validate(const mdem::v1::JobSpec& spec, const KindRulesRegistry& kinds) {
  Report rep;
  check_name(spec, rep);
  if (spec.has_run()) check_run(spec.run(), rep);
  if (spec.has_outputs()) check_outputs(spec.outputs(), rep);
  check_kind(spec, kinds, rep);
  return rep.take();
}

std::vector<FieldError> validate(const mdem::v1::JobSpec& spec) {
  return validate(spec, kind_rules());
}

}  // namespace mdem::spec
