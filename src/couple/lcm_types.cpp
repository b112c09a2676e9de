#include "couple/lcm_types.hpp"

#include <algorithm>
#include <cctype>
#include <fstream>
#include <sstream>

#include "core/errors.hpp"

namespace builtscene::couple {
namespace {

struct Token {
  std::string text;
  std::size_t line = 0;
};

std::vector<Token> tokenize(const std::string& text, const std::string& file) {
  std::vector<Token> out;
  std::size_t line = 1;
  std::size_t i = 0;
  const std::size_t n = text.size();
  while (i < n) {
    const char c = text[i];
    if (c == '\n') { ++line; ++i; continue; }
    if (std::isspace(static_cast<unsigned char>(c))) { ++i; continue; }
    if (c == '/' && i + 1 < n && text[i + 1] == '/') {
      while (i < n && text[i] != '\n') ++i;
      continue;
    }
    if (c == '/' && i + 1 < n && text[i + 1] == '*') {
      const std::size_t start_line = line;
      i += 2;
      while (i + 1 < n && !(text[i] == '*' && text[i + 1] == '/')) {
        if (text[i] == '\n') ++line;
        ++i;
      }
      if (i + 1 >= n) throw_input_error(file, start_line, "unterminated comment");
      i += 2;
      continue;
    }
    if (std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '.' || c == '-' || c == '+') {
      std::size_t j = i;
      while (j < n && (std::isalnum(static_cast<unsigned char>(text[j])) || text[j] == '_' || text[j] == '.' ||
                       ((text[j] == '-' || text[j] == '+') && (j == i || text[j - 1] == 'e' || text[j - 1] == 'E'))))
        ++j;
      out.push_back({text.substr(i, j - i), line});
      i = j;
      continue;
    }
    if (std::string("{}[];,=").find(c) != std::string::npos) {
      out.push_back({std::string(1, c), line});
      ++i;
      continue;
    }
    throw_input_error(file, line, std::string("unexpected character '") + c + "'");
  }
  return out;
}

bool is_identifier(const std::string& s) {
  if (s.empty() || !(std::isalpha(static_cast<unsigned char>(s[0])) || s[0] == '_')) return false;
  return std::all_of(s.begin(), s.end(), [](char ch) { return std::isalnum(static_cast<unsigned char>(ch)) || ch == '_'; });
}

bool is_integer_literal(const std::string& s) {
  return !s.empty() && std::all_of(s.begin(), s.end(), [](char ch) { return std::isdigit(static_cast<unsigned char>(ch)); });
}

// lcm-gen's hash steps (the arithmetic right shift of a signed 64-bit value is intended).
int64_t hash_update(int64_t v, char c) {
  const auto u = static_cast<uint64_t>(v);
  return static_cast<int64_t>(((u << 8) ^ static_cast<uint64_t>(v >> 55)) + static_cast<uint64_t>(static_cast<int64_t>(c)));
}

int64_t hash_string_update(int64_t v, const std::string& s) {
  v = hash_update(v, static_cast<char>(s.size()));
  for (char c : s) v = hash_update(v, c);
  return v;
}

int64_t struct_base_hash(const LcmStruct& s) {
  int64_t v = 0x12345678;
  for (const auto& m : s.members) {
    v = hash_string_update(v, m.name);
    if (m.primitive != Primitive::kNone) v = hash_string_update(v, primitive_name(m.primitive));
    v = hash_update(v, static_cast<char>(m.dims.size()));
    for (const auto& d : m.dims) {
      v = hash_update(v, static_cast<char>(d.variable ? 1 : 0));
      v = hash_string_update(v, d.size);
    }
  }
  return v;
}

class Parser {
 public:
  Parser(std::vector<Token> tokens, std::string file) : t_(std::move(tokens)), file_(std::move(file)) {}

  std::vector<LcmStruct> parse() {
    std::vector<LcmStruct> out;
    while (pos_ < t_.size()) {
      const Token& tok = next();
      if (tok.text == "package") {
        package_ = next().text;
        expect(";");
      } else if (tok.text == "struct") {
        out.push_back(parse_struct(tok.line));
      } else {
        fail(tok.line, "expected 'package' or 'struct', found '" + tok.text + "'");
      }
    }
    return out;
  }

 private:
  LcmStruct parse_struct(std::size_t line) {
    LcmStruct s;
    const Token& name = next();
    if (!is_identifier(name.text)) fail(name.line, "bad struct name '" + name.text + "'");
    s.full_name = package_.empty() ? name.text : package_ + "." + name.text;
    s.file = file_;
    s.line = line;
    expect("{");
    while (peek().text != "}") {
      const Token& first = next();
      if (first.text == "const") {
        parse_constants(s);
        continue;
      }
      LcmMember proto;
      proto.primitive = primitive_from_name(first.text);
      if (proto.primitive == Primitive::kNone) {
        proto.type_name = first.text.find('.') == std::string::npos && !package_.empty() ? package_ + "." + first.text
                                                                                          : first.text;
      }
      // One or more comma-separated members of this type.
      while (true) {
        LcmMember m = proto;
        const Token& mname = next();
        if (!is_identifier(mname.text)) fail(mname.line, "bad member name '" + mname.text + "'");
        m.name = mname.text;
        if (s.member(m.name)) fail(mname.line, "duplicate member '" + m.name + "' in " + s.full_name);
        while (peek().text == "[") {
          next();
          const Token& size = next();
          LcmDimension d;
          if (is_integer_literal(size.text)) {
            d.size = size.text;
          } else if (is_identifier(size.text)) {
            d.variable = true;
            d.size = size.text;
            const LcmMember* dm = s.member(size.text);
            if (!dm) fail(size.line, "array size '" + size.text + "' must be an earlier member of " + s.full_name);
            if (!dm->dims.empty() || !(dm->primitive == Primitive::kInt8 || dm->primitive == Primitive::kInt16 ||
                                        dm->primitive == Primitive::kInt32 || dm->primitive == Primitive::kInt64))
              fail(size.line, "array size '" + size.text + "' must be a scalar integer member");
          } else {
            fail(size.line, "bad array size '" + size.text + "'");
          }
          m.dims.push_back(d);
          expect("]");
        }
        s.members.push_back(m);
        const Token& sep = next();
        if (sep.text == ";") break;
        if (sep.text != ",") fail(sep.line, "expected ';' or ',' after member '" + m.name + "'");
      }
    }
    expect("}");
    s.base_hash = struct_base_hash(s);
    return s;
  }

  void parse_constants(LcmStruct& s) {
    const Token& type = next();
    const Primitive p = primitive_from_name(type.text);
    if (p == Primitive::kNone || p == Primitive::kString || p == Primitive::kBoolean)
      fail(type.line, "constant type must be numeric, found '" + type.text + "'");
    while (true) {
      LcmConstant c;
      c.type = p;
      c.name = next().text;
      expect("=");
      c.value = next().text;
      s.constants.push_back(c);
      const Token& sep = next();
      if (sep.text == ";") break;
      if (sep.text != ",") fail(sep.line, "expected ';' or ',' after constant '" + c.name + "'");
    }
  }

  const Token& next() {
    if (pos_ >= t_.size()) fail(t_.empty() ? 1 : t_.back().line, "unexpected end of file");
    return t_[pos_++];
  }
  const Token& peek() {
    if (pos_ >= t_.size()) fail(t_.empty() ? 1 : t_.back().line, "unexpected end of file");
    return t_[pos_];
  }
  void expect(const std::string& s) {
    const Token& tok = next();
    if (tok.text != s) fail(tok.line, "expected '" + s + "', found '" + tok.text + "'");
  }
  [[noreturn]] void fail(std::size_t line, const std::string& msg) { throw_input_error(file_, line, msg); }

  std::vector<Token> t_;
  std::string file_;
  std::size_t pos_ = 0;
  std::string package_;
};

}  // namespace

const char* primitive_name(Primitive p) {
  switch (p) {
    case Primitive::kInt8: return "int8_t";
    case Primitive::kInt16: return "int16_t";
    case Primitive::kInt32: return "int32_t";
    case Primitive::kInt64: return "int64_t";
    case Primitive::kFloat: return "float";
    case Primitive::kDouble: return "double";
    case Primitive::kString: return "string";
    case Primitive::kBoolean: return "boolean";
    case Primitive::kByte: return "byte";
    case Primitive::kNone: break;
  }
  return "";
}

Primitive primitive_from_name(const std::string& n) {
  static const std::map<std::string, Primitive> names = {
      {"int8_t", Primitive::kInt8},   {"int16_t", Primitive::kInt16}, {"int32_t", Primitive::kInt32},
      {"int64_t", Primitive::kInt64}, {"float", Primitive::kFloat},   {"double", Primitive::kDouble},
      {"string", Primitive::kString}, {"boolean", Primitive::kBoolean}, {"byte", Primitive::kByte}};
  auto it = names.find(n);
  return it == names.end() ? Primitive::kNone : it->second;
}

const LcmMember* LcmStruct::member(const std::string& name) const {
  for (const auto& m : members)
    if (m.name == name) return &m;
  return nullptr;
}

void TypeRegistry::parse_file(const std::filesystem::path& file) {
  std::ifstream in(file);
  if (!in) throw InputError(located(file, 0, "cannot read message definition file"));
  std::stringstream ss;
  ss << in.rdbuf();
  parse_text(ss.str(), file.string());
}

void TypeRegistry::parse_text(const std::string& text, const std::string& file_name) {
  Parser parser(tokenize(text, file_name), file_name);
  for (auto& s : parser.parse()) {
    auto it = types_.find(s.full_name);
    if (it != types_.end()) {
      if (it->second.base_hash == s.base_hash) continue;  // the same type read twice
      throw_input_error(file_name, s.line,
                        "type " + s.full_name + " is defined differently in " + it->second.file);
    }
    types_.emplace(s.full_name, std::move(s));
  }
}

void TypeRegistry::validate() const {
  for (const auto& [name, s] : types_)
    for (const auto& m : s.members)
      if (m.primitive == Primitive::kNone && !find(m.type_name))
        throw_input_error(s.file, s.line, "member '" + m.name + "' of " + name + " has unknown type '" + m.type_name + "'");
}

const LcmStruct* TypeRegistry::find(const std::string& full_name) const {
  auto it = types_.find(full_name);
  return it == types_.end() ? nullptr : &it->second;
}

const LcmStruct& TypeRegistry::get(const std::string& full_name) const {
  const LcmStruct* s = find(full_name);
  if (!s) {
    std::string known;
    for (const auto& [n, _] : types_) known += (known.empty() ? "" : ", ") + n;
    throw InputError("unknown message type '" + full_name + "' (known: " + known + ")");
  }
  return *s;
}

std::vector<std::string> TypeRegistry::names() const {
  std::vector<std::string> out;
  for (const auto& [n, _] : types_) out.push_back(n);
  return out;
}

uint64_t TypeRegistry::recursive_hash(const LcmStruct& s, std::vector<const LcmStruct*>& parents) const {
  if (std::find(parents.begin(), parents.end(), &s) != parents.end()) return 0;
  parents.push_back(&s);
  uint64_t h = static_cast<uint64_t>(s.base_hash);
  for (const auto& m : s.members)
    if (m.primitive == Primitive::kNone) h += recursive_hash(get(m.type_name), parents);
  parents.pop_back();
  return (h << 1) + ((h >> 63) & 1);
}

uint64_t TypeRegistry::fingerprint(const std::string& full_name) const {
  std::vector<const LcmStruct*> parents;
  return recursive_hash(get(full_name), parents);
}

}  // namespace builtscene::couple
