#pragma once
// Shared by the JSON, YAML and file readers.
#include <string>
#include <string_view>

#include "mdem/spec.h"

namespace mdem::spec::detail {

// parse_json, with errors reported under `field` ("json" or "yaml").
mdem::v1::JobSpec parse_json_as(std::string_view json, const std::string& field);

// Refuses text over kMaxSpecBytes with a SpecError under `field`.
void check_size(std::size_t bytes, const std::string& field, const std::string& what);

}  // namespace mdem::spec::detail
