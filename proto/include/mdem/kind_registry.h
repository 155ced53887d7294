#pragma once
// A registry of job kinds, one per layer (spec rules in proto, job factories in jobs, flag tables
// in the client): each kind is one entry, looked up by its name or by JobSpec's `kind` oneof
// case, so that adding a kind adds an entry and edits no switch. Entry is any struct with
// `std::string name` and `v1::JobSpec::KindCase kind_case`.
#include <stdexcept>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "mdem/v1/job.pb.h"

namespace mdem {

template <class Entry>
class KindRegistry {
 public:
  KindRegistry() = default;
  KindRegistry(std::initializer_list<Entry> entries) {
    for (const Entry& e : entries) add(e);
  }

  // Adds a kind. std::logic_error for an empty name, no oneof case, or a name or case that is
  // registered already.
  void add(Entry e) {
    if (e.name.empty()) throw std::logic_error("a job kind needs a name");
    if (e.kind_case == v1::JobSpec::KIND_NOT_SET)
      throw std::logic_error("job kind '" + e.name + "' names no JobSpec kind case");
    if (find(e.name) || find(e.kind_case))
      throw std::logic_error("job kind '" + e.name + "' is registered twice");
    entries_.push_back(std::move(e));
  }

  const Entry* find(v1::JobSpec::KindCase kind_case) const {
    for (const Entry& e : entries_)
      if (e.kind_case == kind_case) return &e;
    return nullptr;
  }
  const Entry* find(std::string_view name) const {
    for (const Entry& e : entries_)
      if (e.name == name) return &e;
    return nullptr;
  }
  // The kind the spec holds, or nullptr.
  const Entry* of(const v1::JobSpec& spec) const { return find(spec.kind_case()); }

  // In registration order.
  const std::vector<Entry>& all() const { return entries_; }
  // "twist, compression"
  std::string names() const {
    std::string s;
    for (const Entry& e : entries_) s += (s.empty() ? "" : ", ") + e.name;
    return s;
  }

 private:
  std::vector<Entry> entries_;
};

}  // namespace mdem
