#pragma once
// What protobuf parsed but could not read: fields a message does not have, and fields that
// arrived with another wire type than their declared one (a twist's `layers` sent as bytes).
// Protobuf keeps both in the message's unknown-field set and leaves the field at its default, so
// a request carrying them would run with values its sender did not give: mdemd refuses it.
#include <google/protobuf/message.h>

#include <string>

namespace mdem::server {

// Empty when every field of `m` and of its nested messages was read; otherwise one line per
// unreadable field naming its number, wire type and path (e.g. "spec.twist: field 1 ('layers',
// int32) arrived as length-delimited bytes"), at most `max_lines`.
std::string unreadable_fields(const google::protobuf::Message& m, int max_lines = 20);

}  // namespace mdem::server
