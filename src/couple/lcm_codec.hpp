#pragma once
// Encodes and decodes LCM messages of a runtime-parsed type to and from JSON values
// (objects keyed by member name; arrays as nested JSON arrays). Byte-for-byte LCM's wire
// format: an 8-byte big-endian fingerprint, then the members big-endian, nested structs
// without their own fingerprint, strings as int32 length (with the terminating NUL).
#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "couple/lcm_types.hpp"

namespace builtscene::couple {

class LcmCodec {
 public:
  LcmCodec(const TypeRegistry& types, std::string type_name);

  const std::string& type_name() const { return type_; }
  uint64_t fingerprint() const { return fingerprint_; }

  // Throws InputError naming the member when `value` lacks a member or has the wrong shape.
  std::vector<uint8_t> encode(const nlohmann::json& value) const;
  void encode(const nlohmann::json& value, std::vector<uint8_t>& out) const;
  // Throws InputError on a wrong fingerprint or truncated data.
  nlohmann::json decode(const uint8_t* data, std::size_t size) const;
  nlohmann::json decode(const std::vector<uint8_t>& bytes) const { return decode(bytes.data(), bytes.size()); }

  // The int64 member `member` of an encoded message; fast when only fixed-size members
  // precede it. Throws InputError on a foreign fingerprint.
  int64_t read_int64(const uint8_t* data, std::size_t size, const std::string& member) const;

  // A value with every member zero / empty (variable arrays empty).
  nlohmann::json zero() const;

 private:
  const TypeRegistry* types_;
  std::string type_;
  uint64_t fingerprint_;
};

// Reads the fingerprint at the start of an encoded message (0 if too short).
uint64_t peek_fingerprint(const uint8_t* data, std::size_t size);

}  // namespace builtscene::couple
