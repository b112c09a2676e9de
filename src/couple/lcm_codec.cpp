#include "couple/lcm_codec.hpp"

#include <bit>
#include <cstring>

#include "core/errors.hpp"

namespace builtscene::couple {
namespace {

using nlohmann::json;

template <typename T>
void put_be(std::vector<uint8_t>& out, T v) {
  using U = std::make_unsigned_t<std::conditional_t<std::is_floating_point_v<T>,
                                                    std::conditional_t<sizeof(T) == 4, int32_t, int64_t>, T>>;
  U u;
  std::memcpy(&u, &v, sizeof(T));
  for (int i = static_cast<int>(sizeof(T)) - 1; i >= 0; --i) out.push_back(static_cast<uint8_t>(u >> (8 * i)));
}

class Reader {
 public:
  Reader(const uint8_t* d, std::size_t n, const std::string& type) : d_(d), n_(n), type_(type) {}
  template <typename T>
  T get() {
    using U = std::make_unsigned_t<std::conditional_t<std::is_floating_point_v<T>,
                                                      std::conditional_t<sizeof(T) == 4, int32_t, int64_t>, T>>;
    need(sizeof(T));
    U u = 0;
    for (std::size_t i = 0; i < sizeof(T); ++i) u = static_cast<U>((u << 8) | d_[p_ + i]);
    p_ += sizeof(T);
    T v;
    std::memcpy(&v, &u, sizeof(T));
    return v;
  }
  std::string get_string() {
    const int32_t len = get<int32_t>();
    if (len < 1) throw InputError("malformed " + type_ + " message: bad string length");
    need(static_cast<std::size_t>(len));
    std::string s(reinterpret_cast<const char*>(d_ + p_), static_cast<std::size_t>(len - 1));
    p_ += static_cast<std::size_t>(len);
    return s;
  }
  std::size_t remaining() const { return n_ - p_; }

 private:
  void need(std::size_t k) {
    if (p_ + k > n_) throw InputError("malformed " + type_ + " message: truncated (" + std::to_string(n_) + " bytes)");
  }
  const uint8_t* d_;
  std::size_t n_;
  std::size_t p_ = 0;
  const std::string& type_;
};

int64_t as_int(const json& v, const std::string& where) {
  if (v.is_number_integer()) return v.get<int64_t>();
  if (v.is_boolean()) return v.get<bool>() ? 1 : 0;
  if (v.is_number_float()) {
    const double d = v.get<double>();
    if (d == static_cast<double>(static_cast<int64_t>(d))) return static_cast<int64_t>(d);
  }
  throw InputError("member " + where + ": expected an integer, got " + v.dump());
}

double as_double(const json& v, const std::string& where) {
  if (v.is_number()) return v.get<double>();
  throw InputError("member " + where + ": expected a number, got " + v.dump());
}

class Encoder {
 public:
  Encoder(const TypeRegistry& t, std::vector<uint8_t>& out) : t_(t), out_(out) {}

  void encode_struct(const LcmStruct& s, const json& v, const std::string& path) {
    if (!v.is_object()) throw InputError("member " + path + ": expected an object of type " + s.full_name);
    for (const auto& m : s.members) {
      const std::string where = path.empty() ? m.name : path + "." + m.name;
      auto it = v.find(m.name);
      if (it == v.end()) {
        // A variable-size member may be left out; it is taken from the array it sizes.
        if (const json* inferred = infer_size(s, v, m.name)) {
          encode_scalar(m, *inferred, where);
          continue;
        }
        throw InputError("member " + where + " of " + s.full_name + " is missing");
      }
      encode_member(s, m, v, *it, 0, where);
    }
  }

 private:
  const json* infer_size(const LcmStruct& s, const json& v, const std::string& size_member) {
    for (const auto& m : s.members)
      if (!m.dims.empty() && m.dims[0].variable && m.dims[0].size == size_member && v.contains(m.name) &&
          v[m.name].is_array()) {
        tmp_ = v[m.name].size();
        return &tmp_;
      }
    return nullptr;
  }

  std::size_t dim_size(const LcmStruct& s, const json& obj, const LcmDimension& d, const std::string& where) {
    if (!d.variable) return std::stoull(d.size);
    const json* n = obj.contains(d.size) ? &obj[d.size] : infer_size(s, obj, d.size);
    if (!n) throw InputError("member " + where + ": size member '" + d.size + "' is missing");
    const int64_t k = as_int(*n, d.size);
    if (k < 0) throw InputError("member " + where + ": negative size " + std::to_string(k));
    return static_cast<std::size_t>(k);
  }

  void encode_member(const LcmStruct& s, const LcmMember& m, const json& obj, const json& v, std::size_t dim,
                     const std::string& where) {
    if (dim == m.dims.size()) {
      if (m.primitive == Primitive::kNone)
        encode_struct(t_.get(m.type_name), v, where);
      else
        encode_scalar(m, v, where);
      return;
    }
    const std::size_t n = dim_size(s, obj, m.dims[dim], where);
    if (!v.is_array() || v.size() != n)
      throw InputError("member " + where + ": expected an array of " + std::to_string(n) + " elements, got " +
                       (v.is_array() ? std::to_string(v.size()) : v.type_name()));
    for (std::size_t i = 0; i < n; ++i) encode_member(s, m, obj, v[i], dim + 1, where + "[" + std::to_string(i) + "]");
  }

  void encode_scalar(const LcmMember& m, const json& v, const std::string& where) {
    switch (m.primitive) {
      case Primitive::kInt8: put_be(out_, checked<int8_t>(as_int(v, where), where)); break;
      case Primitive::kInt16: put_be(out_, checked<int16_t>(as_int(v, where), where)); break;
      case Primitive::kInt32: put_be(out_, checked<int32_t>(as_int(v, where), where)); break;
      case Primitive::kInt64: put_be(out_, as_int(v, where)); break;
      case Primitive::kByte: put_be(out_, static_cast<uint8_t>(checked_byte(as_int(v, where), where))); break;
      case Primitive::kBoolean: {
        if (!v.is_boolean() && !v.is_number_integer()) throw InputError("member " + where + ": expected a boolean");
        put_be(out_, static_cast<int8_t>(v.is_boolean() ? v.get<bool>() : v.get<int64_t>() != 0));
        break;
      }
      case Primitive::kFloat: put_be(out_, static_cast<float>(as_double(v, where))); break;
      case Primitive::kDouble: put_be(out_, as_double(v, where)); break;
      case Primitive::kString: {
        if (!v.is_string()) throw InputError("member " + where + ": expected a string");
        const auto& str = v.get_ref<const std::string&>();
        put_be(out_, static_cast<int32_t>(str.size() + 1));
        out_.insert(out_.end(), str.begin(), str.end());
        out_.push_back(0);
        break;
      }
      case Primitive::kNone: break;
    }
  }

  template <typename T>
  T checked(int64_t v, const std::string& where) {
    if (v < std::numeric_limits<T>::min() || v > std::numeric_limits<T>::max())
      throw InputError("member " + where + ": value " + std::to_string(v) + " out of range");
    return static_cast<T>(v);
  }
  int64_t checked_byte(int64_t v, const std::string& where) {
    if (v < 0 || v > 255) throw InputError("member " + where + ": byte value " + std::to_string(v) + " out of range");
    return v;
  }

  const TypeRegistry& t_;
  std::vector<uint8_t>& out_;
  json tmp_;
};

class Decoder {
 public:
  Decoder(const TypeRegistry& t, Reader& r) : t_(t), r_(r) {}

  json decode_struct(const LcmStruct& s) {
    json obj = json::object();
    for (const auto& m : s.members) obj[m.name] = decode_member(m, obj, 0);
    return obj;
  }

 private:
  json decode_member(const LcmMember& m, const json& obj, std::size_t dim) {
    if (dim == m.dims.size()) {
      if (m.primitive == Primitive::kNone) return decode_struct(t_.get(m.type_name));
      return decode_scalar(m.primitive);
    }
    const auto& d = m.dims[dim];
    int64_t n = d.variable ? obj.at(d.size).get<int64_t>() : std::stoll(d.size);
    if (n < 0 || static_cast<std::size_t>(n) > r_.remaining() + 1)
      throw InputError("malformed message: array " + m.name + " size " + std::to_string(n) + " exceeds the data");
    json arr = json::array();
    for (int64_t i = 0; i < n; ++i) arr.push_back(decode_member(m, obj, dim + 1));
    return arr;
  }

  json decode_scalar(Primitive p) {
    switch (p) {
      case Primitive::kInt8: return r_.get<int8_t>();
      case Primitive::kInt16: return r_.get<int16_t>();
      case Primitive::kInt32: return r_.get<int32_t>();
      case Primitive::kInt64: return r_.get<int64_t>();
      case Primitive::kByte: return r_.get<uint8_t>();
      case Primitive::kBoolean: return r_.get<int8_t>() != 0;
      case Primitive::kFloat: return r_.get<float>();
      case Primitive::kDouble: return r_.get<double>();
      case Primitive::kString: return r_.get_string();
      case Primitive::kNone: break;
    }
    return nullptr;
  }

  const TypeRegistry& t_;
  Reader& r_;
};

json zero_member(const TypeRegistry& t, const LcmMember& m, std::size_t dim);

json zero_struct(const TypeRegistry& t, const LcmStruct& s) {
  json obj = json::object();
  for (const auto& m : s.members) obj[m.name] = zero_member(t, m, 0);
  return obj;
}

json zero_member(const TypeRegistry& t, const LcmMember& m, std::size_t dim) {
  if (dim == m.dims.size()) {
    switch (m.primitive) {
      case Primitive::kNone: return zero_struct(t, t.get(m.type_name));
      case Primitive::kString: return "";
      case Primitive::kBoolean: return false;
      case Primitive::kFloat:
      case Primitive::kDouble: return 0.0;
      default: return 0;
    }
  }
  json arr = json::array();
  if (!m.dims[dim].variable)
    for (std::size_t i = 0; i < std::stoull(m.dims[dim].size); ++i) arr.push_back(zero_member(t, m, dim + 1));
  return arr;
}

}  // namespace

LcmCodec::LcmCodec(const TypeRegistry& types, std::string type_name)
    : types_(&types), type_(std::move(type_name)), fingerprint_(types.fingerprint(type_)) {}

std::vector<uint8_t> LcmCodec::encode(const json& value) const {
  std::vector<uint8_t> out;
  encode(value, out);
  return out;
}

void LcmCodec::encode(const json& value, std::vector<uint8_t>& out) const {
  out.clear();
  put_be(out, fingerprint_);
  Encoder(*types_, out).encode_struct(types_->get(type_), value, "");
}

json LcmCodec::decode(const uint8_t* data, std::size_t size) const {
  Reader r(data, size, type_);
  const uint64_t fp = r.get<uint64_t>();
  if (fp != fingerprint_) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "0x%016llx, expected 0x%016llx", static_cast<unsigned long long>(fp),
                  static_cast<unsigned long long>(fingerprint_));
    throw InputError("message is not of type " + type_ + ": fingerprint " + buf);
  }
  return Decoder(*types_, r).decode_struct(types_->get(type_));
}

namespace {
// Bytes before `member` when every earlier member has a fixed size; -1 otherwise.
long fixed_offset(const TypeRegistry& t, const LcmStruct& s, const std::string& member) {
  long off = 8;
  for (const auto& m : s.members) {
    if (m.name == member) return m.primitive == Primitive::kInt64 && m.dims.empty() ? off : -1;
    long size = 0;
    switch (m.primitive) {
      case Primitive::kInt8: case Primitive::kByte: case Primitive::kBoolean: size = 1; break;
      case Primitive::kInt16: size = 2; break;
      case Primitive::kInt32: case Primitive::kFloat: size = 4; break;
      case Primitive::kInt64: case Primitive::kDouble: size = 8; break;
      default: return -1;  // strings and nested structs vary
    }
    (void)t;
    for (const auto& d : m.dims) {
      if (d.variable) return -1;
      size *= std::stol(d.size);
    }
    off += size;
  }
  return -1;
}
}  // namespace

int64_t LcmCodec::read_int64(const uint8_t* data, std::size_t size, const std::string& member) const {
  const long off = fixed_offset(*types_, types_->get(type_), member);
  if (off < 0) {
    const json v = decode(data, size);
    return v.at(member).get<int64_t>();
  }
  if (peek_fingerprint(data, size) != fingerprint_) decode(data, size);  // throws with the details
  if (size < static_cast<std::size_t>(off) + 8) throw InputError("malformed " + type_ + " message: truncated");
  uint64_t v = 0;
  for (long i = 0; i < 8; ++i) v = (v << 8) | data[off + i];
  return static_cast<int64_t>(v);
}

json LcmCodec::zero() const { return zero_struct(*types_, types_->get(type_)); }

uint64_t peek_fingerprint(const uint8_t* data, std::size_t size) {
  if (size < 8) return 0;
  uint64_t v = 0;
  for (int i = 0; i < 8; ++i) v = (v << 8) | data[i];
  return v;
}

}  // namespace builtscene::couple
