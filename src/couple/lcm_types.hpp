#pragma once
// The LCM type language (.lcm files): a runtime parser and LCM's type fingerprint.
// Encoding rules and the fingerprint follow lcm-gen exactly (checked against lcm-gen's
// generated code in tests/couple), so lcm-spy, lcm-logger and lcm-gen code in any
// language read our channels.
#include <cstdint>
#include <filesystem>
#include <map>
#include <memory>
#include <string>
#include <vector>

namespace builtscene::couple {

enum class Primitive { kNone, kInt8, kInt16, kInt32, kInt64, kFloat, kDouble, kString, kBoolean, kByte };

// Name as written in .lcm ("int8_t", "double", ...); empty for kNone.
const char* primitive_name(Primitive p);
Primitive primitive_from_name(const std::string& name);

struct LcmDimension {
  bool variable = false;  // true: size is the value of member `size`; false: `size` is a literal
  std::string size;
};

struct LcmMember {
  std::string name;
  Primitive primitive = Primitive::kNone;
  std::string type_name;  // full name of a nested struct when primitive == kNone
  std::vector<LcmDimension> dims;
};

struct LcmConstant {
  std::string name;
  Primitive type = Primitive::kNone;
  std::string value;
};

struct LcmStruct {
  std::string full_name;  // "package.name" or "name"
  std::string file;
  std::size_t line = 0;
  std::vector<LcmMember> members;
  std::vector<LcmConstant> constants;
  int64_t base_hash = 0;  // lcm-gen's per-struct hash (members only, no nesting)
  const LcmMember* member(const std::string& name) const;
};

// A set of parsed types. Nested names resolve against the struct's package first,
// then as a full name. Fingerprints include nested types recursively, as lcm-gen does.
class TypeRegistry {
 public:
  // Parses one .lcm file; throws InputError naming file:line on a syntax error.
  void parse_file(const std::filesystem::path& file);
  void parse_text(const std::string& text, const std::string& file_name);

  // Checks that nested types exist and variable dimensions name earlier integer members.
  void validate() const;

  const LcmStruct* find(const std::string& full_name) const;
  const LcmStruct& get(const std::string& full_name) const;  // throws InputError
  std::vector<std::string> names() const;

  // The 64-bit fingerprint that prefixes every encoded message of this type.
  uint64_t fingerprint(const std::string& full_name) const;

 private:
  uint64_t recursive_hash(const LcmStruct& s, std::vector<const LcmStruct*>& parents) const;
  std::map<std::string, LcmStruct> types_;
};

}  // namespace builtscene::couple
