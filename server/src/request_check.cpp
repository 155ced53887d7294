#include "request_check.h"

#include <google/protobuf/descriptor.h>
#include <google/protobuf/unknown_field_set.h>

#include <vector>

namespace mdem::server {
namespace {

namespace pb = google::protobuf;

const char* wire_name(pb::UnknownField::Type t) {
  switch (t) {
    case pb::UnknownField::TYPE_VARINT:
      return "a varint";
    case pb::UnknownField::TYPE_FIXED32:
      return "a 32-bit value";
    case pb::UnknownField::TYPE_FIXED64:
      return "a 64-bit value";
    case pb::UnknownField::TYPE_LENGTH_DELIMITED:
      return "length-delimited bytes";
    case pb::UnknownField::TYPE_GROUP:
      return "a group";
  }
  return "an unknown wire type";
}

void walk(const pb::Message& m, const std::string& path, int max_lines,
          std::vector<std::string>& out) {
  const pb::Descriptor* d = m.GetDescriptor();
  const pb::Reflection* r = m.GetReflection();
  const pb::UnknownFieldSet& unknown = r->GetUnknownFields(m);
  const std::string where = path.empty() ? d->name() : path;
  for (int i = 0; i < unknown.field_count() && static_cast<int>(out.size()) < max_lines; ++i) {
    const pb::UnknownField& f = unknown.field(i);
    const pb::FieldDescriptor* known = d->FindFieldByNumber(f.number());
    std::string line = where + ": field " + std::to_string(f.number());
    if (known)
      line += " ('" + known->name() + "', " + known->type_name() + ") arrived as " +
              wire_name(f.type()) + ", which is not how a " + known->type_name() + " is sent";
    else
      line += " (" + std::string(wire_name(f.type())) + ") is not a field of " + d->full_name();
    out.push_back(std::move(line));
  }
  std::vector<const pb::FieldDescriptor*> fields;
  r->ListFields(m, &fields);
  for (const pb::FieldDescriptor* f : fields) {
    if (f->cpp_type() != pb::FieldDescriptor::CPPTYPE_MESSAGE) continue;
    const std::string sub = path.empty() ? f->name() : path + "." + f->name();
    if (f->is_repeated()) {
      for (int k = 0; k < r->FieldSize(m, f) && static_cast<int>(out.size()) < max_lines; ++k)
        walk(r->GetRepeatedMessage(m, f, k), sub + "[" + std::to_string(k) + "]", max_lines, out);
    } else {
      walk(r->GetMessage(m, f), sub, max_lines, out);
    }
  }
}

}  // namespace

std::string unreadable_fields(const pb::Message& m, int max_lines) {
  std::vector<std::string> lines;
  walk(m, "", max_lines, lines);
  std::string out;
  for (const std::string& l : lines) out += (out.empty() ? "" : "\n") + l;
  return out;
}

}  // namespace mdem::server
