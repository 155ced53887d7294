// `--vary` of `mdem study`: names resolved through the job spec's descriptor (numeric scalars
// only) and the CLI's flag tables, values through the spec rules.
#include "study_vary.h"

#include <google/protobuf/descriptor.h>
#include <google/protobuf/message.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <optional>
#include <set>

#include "mdem/suggest.h"

namespace mdem::cli {
namespace {

using google::protobuf::FieldDescriptor;
using google::protobuf::Message;

// A single number: not a list, and not a message, string, bool or enum.
bool numeric(const FieldDescriptor* f) {
  using T = FieldDescriptor::CppType;
  const T t = f->cpp_type();
  return !f->is_repeated() && t != T::CPPTYPE_MESSAGE && t != T::CPPTYPE_STRING &&
         t != T::CPPTYPE_BOOL && t != T::CPPTYPE_ENUM;
}

bool is_integer(const FieldDescriptor* f) {
  return f->cpp_type() != FieldDescriptor::CPPTYPE_DOUBLE &&
         f->cpp_type() != FieldDescriptor::CPPTYPE_FLOAT;
}

// The field at a dotted path of JobSpec ("run.safety"), or nullptr.
const FieldDescriptor* field_at(const std::string& path) {
  const google::protobuf::Descriptor* d = v1::JobSpec::descriptor();
  const FieldDescriptor* f = nullptr;
  for (const std::string& part : split(path, '.')) {
    if (!d) return nullptr;
    f = d->FindFieldByName(part);
    if (!f) return nullptr;
    d = f->cpp_type() == FieldDescriptor::CPPTYPE_MESSAGE ? f->message_type() : nullptr;
  }
  return f;
}

// Accepted name -> dotted path: paths, their last components when unique, and flags that set
// one numeric field.
std::map<std::string, std::string> name_table(const SpecKind& kind) {
  std::map<std::string, std::string> names;
  std::map<std::string, int> last_count;
  const std::vector<std::string> paths = variable_fields(kind);
  for (const std::string& p : paths) {
    names[p] = p;
    ++last_count[short_name(p)];
  }
  for (const std::string& p : paths)
    if (last_count[short_name(p)] == 1) names.emplace(short_name(p), p);
  std::map<std::string, std::set<std::string>> by_flag;
  for (const auto* table : {&common_flag_fields(), &kind.flag_fields()})
    for (const auto& [flag, field] : *table) by_flag[flag.substr(2)].insert(field);
  for (const auto& [flag, fields] : by_flag)
    if (fields.size() == 1 && std::count(paths.begin(), paths.end(), *fields.begin()))
      names.emplace(flag, *fields.begin());
  return names;
}

std::string unknown_field(const SpecKind& kind, const std::string& name,
                          const std::map<std::string, std::string>& names) {
  std::vector<std::string> known;
  for (const auto& [n, path] : names) known.push_back(n);
  const std::optional<std::string> closest = closest_name(name, known);
  std::string list;
  for (const std::string& p : variable_fields(kind)) list += (list.empty() ? "" : ", ") + p;
  std::string msg = "--vary: '" + name + "' is not a numeric field of a " + kind.name + " spec";
  if (closest) msg += " (did you mean '" + *closest + "'?)";
  return msg + " (allowed: " + list + ", by dotted path, own name or flag)";
}

void set_value(Message& msg, const std::string& path, double v) {
  Message* m = &msg;
  const std::vector<std::string> parts = split(path, '.');
  for (std::size_t i = 0; i + 1 < parts.size(); ++i) {
    const FieldDescriptor* f = m->GetDescriptor()->FindFieldByName(parts[i]);
    m = m->GetReflection()->MutableMessage(m, f);
  }
  const FieldDescriptor* f = m->GetDescriptor()->FindFieldByName(parts.back());
  const auto* r = m->GetReflection();
  switch (f->cpp_type()) {
    case FieldDescriptor::CPPTYPE_DOUBLE:
      return r->SetDouble(m, f, v);
    case FieldDescriptor::CPPTYPE_FLOAT:
      return r->SetFloat(m, f, static_cast<float>(v));
    case FieldDescriptor::CPPTYPE_INT32:
      return r->SetInt32(m, f, static_cast<std::int32_t>(v));
    case FieldDescriptor::CPPTYPE_INT64:
      return r->SetInt64(m, f, static_cast<std::int64_t>(v));
    case FieldDescriptor::CPPTYPE_UINT32:
      return r->SetUInt32(m, f, static_cast<std::uint32_t>(v));
    default:
      return r->SetUInt64(m, f, static_cast<std::uint64_t>(v));
  }
}

// One value of a --vary list: finite, whole for an integer field (and within what the field's
// proto type holds; the spec rules check the range).
double parse_value(const std::string& name, const std::string& item, bool integer) {
  const std::string flag = "--vary " + name;
  if (item.empty()) throw UsageError(flag + ": an empty value in the list (allowed: v1,v2,...)");
  const double v = parse_number(flag, item, "finite numbers separated by commas");
  if (integer && (v != std::floor(v) || std::abs(v) > 9.0e15))
    throw UsageError(flag + ": " + item + " is not a whole number (the field is an integer)");
  return v;
}

std::string spec_error_text(const spec::SpecError& e) {
  std::string text;
  for (const spec::FieldError& fe : e.errors())
    text += (text.empty() ? "" : "; ") + fe.field + ": " + fe.message;
  return text;
}

}  // namespace

std::string short_name(const std::string& path) {
  const auto dot = path.rfind('.');
  return dot == std::string::npos ? path : path.substr(dot + 1);
}

std::vector<std::string> variable_fields(const SpecKind& kind) {
  std::vector<std::string> out;
  const google::protobuf::Descriptor* spec = v1::JobSpec::descriptor();
  for (const char* top : {"seed", "run", "outputs"}) {
    const FieldDescriptor* f = spec->FindFieldByName(top);
    if (numeric(f)) out.push_back(top);
    if (f->cpp_type() != FieldDescriptor::CPPTYPE_MESSAGE) continue;
    for (int i = 0; i < f->message_type()->field_count(); ++i)
      if (const FieldDescriptor* g = f->message_type()->field(i); numeric(g))
        out.push_back(std::string(top) + "." + g->name());
  }
  if (const FieldDescriptor* k = spec->FindFieldByName(kind.name); k && k->message_type())
    for (int i = 0; i < k->message_type()->field_count(); ++i)
      if (const FieldDescriptor* g = k->message_type()->field(i); numeric(g))
        out.push_back(kind.name + "." + g->name());
  return out;
}

VariedField parse_vary(const SpecKind& kind, const std::string& text) {
  const auto eq = text.find('=');
  if (eq == std::string::npos)
    throw UsageError("--vary: '" + text + "' has no '=' (allowed: FIELD=v1,v2,..., e.g. " +
                     "safety=0.6,0.3,0.15)");
  const std::string name = text.substr(0, eq), list = text.substr(eq + 1);
  const auto names = name_table(kind);
  const auto it = names.find(name);
  if (it == names.end()) throw UsageError(unknown_field(kind, name, names));
  VariedField v;
  v.path = it->second;
  v.integer = is_integer(field_at(v.path));
  if (list.empty())
    throw UsageError("--vary " + name + ": no values (allowed: one or more numbers, v1,v2,...)");
  // Counted before parsing, so that a huge list is one error, not a long wait.
  if (std::count(list.begin(), list.end(), ',') + 1 > static_cast<long>(kMaxStudyRuns))
    throw UsageError("--vary " + name + ": more than " + std::to_string(kMaxStudyRuns) +
                     " values (allowed: at most " + std::to_string(kMaxStudyRuns) +
                     " runs in a study)");
  std::vector<std::string> items = split(list, ',');
  if (list.back() == ',') items.push_back("");
  for (const std::string& item : items) {
    const double x = parse_value(name, item, v.integer);
    if (std::find(v.values.begin(), v.values.end(), x) != v.values.end())
      throw UsageError("--vary " + name + ": " + item +
                       " is listed twice (allowed: each value once)");
    v.values.push_back(x);
  }
  return v;
}

std::vector<std::vector<double>> study_points(const std::vector<VariedField>& fields) {
  if (fields.empty())
    throw UsageError("--vary: missing (allowed: one or more --vary FIELD=v1,v2,...)");
  double count = 1;
  std::set<std::string> seen;
  for (const VariedField& f : fields) {
    if (!seen.insert(f.path).second)
      throw UsageError("--vary: " + f.path + " is varied twice (allowed: each field once)");
    count *= static_cast<double>(f.values.size());
  }
  if (count > static_cast<double>(kMaxStudyRuns))
    throw UsageError("--vary: " + spec::number_text(count) + " runs (the product of the lists) " +
                     "is more than a study may have (allowed: at most " +
                     std::to_string(kMaxStudyRuns) + ")");
  std::vector<std::vector<double>> points = {{}};
  for (const VariedField& f : fields) {
    std::vector<std::vector<double>> next;
    for (const auto& p : points)
      for (double v : f.values) {
        next.push_back(p);
        next.back().push_back(v);
      }
    points = std::move(next);
  }
  return points;
}

v1::JobSpec varied_spec(const v1::JobSpec& base, const std::vector<VariedField>& fields,
                        const std::vector<double>& point) {
  v1::JobSpec spec = base;
  for (std::size_t i = 0; i < fields.size(); ++i) {
    // Out of what the proto type holds: refused here, before a cast would wrap it.
    const FieldDescriptor* f = field_at(fields[i].path);
    const double v = point[i];
    const bool is_unsigned = f->cpp_type() == FieldDescriptor::CPPTYPE_UINT32 ||
                             f->cpp_type() == FieldDescriptor::CPPTYPE_UINT64;
    const bool is_32 = f->cpp_type() == FieldDescriptor::CPPTYPE_INT32 ||
                       f->cpp_type() == FieldDescriptor::CPPTYPE_UINT32;
    if (fields[i].integer && ((is_unsigned && v < 0) || (is_32 && std::abs(v) > 2147483647.0)))
      throw UsageError("--vary " + short_name(fields[i].path) + "=" + spec::number_text(v) + ": " +
                       fields[i].path + " cannot hold it (allowed: " +
                       (is_unsigned ? "a whole number >= 0" : "a 32-bit whole number") + ")");
    set_value(spec, fields[i].path, v);
  }
  try {
    return spec::finalize(spec);
  } catch (const spec::SpecError& e) {
    throw UsageError("--vary " + point_text(fields, point) + ": " + spec_error_text(e));
  }
}

void check_study(const v1::JobSpec& base, const std::vector<VariedField>& fields) {
  for (const VariedField& f : fields)
    if (f.path == "run.safety" && base.run().has_dt_ps())
      throw UsageError("--vary safety: the spec fixes the time step (--dt " +
                       spec::number_text(base.run().dt_ps()) +
                       " ps), so the safety factor would change nothing (allowed: vary safety "
                       "with --dt auto, or vary dt_ps)");
  // Each value on its own first (so the message names one value), then every point.
  for (std::size_t i = 0; i < fields.size(); ++i)
    for (double v : fields[i].values) varied_spec(base, {fields[i]}, {v});
  for (const auto& p : study_points(fields)) varied_spec(base, fields, p);
}

std::string point_text(const std::vector<VariedField>& fields, const std::vector<double>& point) {
  std::string s;
  for (std::size_t i = 0; i < fields.size() && i < point.size(); ++i)
    s += (s.empty() ? "" : ", ") + short_name(fields[i].path) + "=" + spec::number_text(point[i]);
  return s;
}

bool integer_field(const std::string& path) {
  const FieldDescriptor* f = field_at(path);
  return f && numeric(f) && is_integer(f);
}

}  // namespace mdem::cli
