// The vocabulary file (.bsvoc), little-endian:
//   "BSVOCAB\n" | u32 version (1) | u32 kind (0 binary, 1 float) | u32 cols | u32 k | u32 levels
//   | u32 node_count | node_count x (i32 parent, f64 weight, centre: cols bytes or cols f32)
//   | u64 FNV-1a of every byte before it.
// Children, depths and word ids are rebuilt from the parents (words = leaves in node order),
// so the file cannot describe an inconsistent tree beyond what load() checks.
#include <bit>
#include <cmath>
#include <cstring>
#include <fstream>
#include <iterator>
#include <string>

#include "core/checksum.hpp"
#include "core/errors.hpp"
#include "features/bow_vocabulary.hpp"

namespace builtscene {

namespace {

constexpr char kVocabularyMagic[8] = {'B', 'S', 'V', 'O', 'C', 'A', 'B', '\n'};
constexpr std::uint32_t kVocabularyVersion = 1;

static_assert(std::endian::native == std::endian::little, "the vocabulary file is written in native little-endian");

template <typename T>
void put(std::string& out, T v) {
  char b[sizeof(T)];
  std::memcpy(b, &v, sizeof(T));
  out.append(b, sizeof(T));
}

// Reads fields off a byte buffer; running past the end is a truncated file.
class Reader {
 public:
  Reader(const std::string& bytes, std::size_t end, const std::filesystem::path& path)
      : bytes_(bytes), end_(end), path_(path) {}
  template <typename T>
  T get(const char* field) {
    T v;
    raw(&v, sizeof(T), field);
    return v;
  }
  void raw(void* out, std::size_t n, const char* field) {
    if (pos_ + n > end_) throw InputError(located(path_, 0, std::string("truncated vocabulary file (reading ") + field + ")"));
    std::memcpy(out, bytes_.data() + pos_, n);
    pos_ += n;
  }
  std::size_t position() const { return pos_; }

 private:
  const std::string& bytes_;
  std::size_t end_;
  const std::filesystem::path& path_;
  std::size_t pos_ = 0;
};

}  // namespace

void BowVocabulary::save(const std::filesystem::path& path) const {
  if (empty()) throw Failure("vocabulary: nothing to save (empty vocabulary)");
  std::string out(kVocabularyMagic, sizeof(kVocabularyMagic));
  put<std::uint32_t>(out, kVocabularyVersion);
  put<std::uint32_t>(out, kind_ == DescriptorKind::kBinary ? 0u : 1u);
  put<std::uint32_t>(out, static_cast<std::uint32_t>(cols_));
  put<std::uint32_t>(out, static_cast<std::uint32_t>(k_));
  put<std::uint32_t>(out, static_cast<std::uint32_t>(levels_));
  put<std::uint32_t>(out, static_cast<std::uint32_t>(nodes_.size()));
  const std::size_t row_bytes = centres_.elemSize() * static_cast<std::size_t>(cols_);
  for (std::size_t i = 0; i < nodes_.size(); ++i) {
    put<std::int32_t>(out, nodes_[i].parent);
    put<double>(out, nodes_[i].weight);
    out.append(reinterpret_cast<const char*>(centres_.ptr(static_cast<int>(i))), row_bytes);
  }
  put<std::uint64_t>(out, fnv1a64(out.data(), out.size()));
  std::ofstream f(path, std::ios::binary | std::ios::trunc);
  if (!f) throw InputError(located(path, 0, "cannot write vocabulary file"));
  f.write(out.data(), static_cast<std::streamsize>(out.size()));
  if (!f) throw InputError(located(path, 0, "write failed"));
}

BowVocabulary BowVocabulary::load(const std::filesystem::path& path) {
  std::ifstream f(path, std::ios::binary);
  if (!f) throw InputError(located(path, 0, "cannot open vocabulary file"));
  const std::string bytes((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
  if (bytes.size() < sizeof(kVocabularyMagic) || std::memcmp(bytes.data(), kVocabularyMagic, sizeof(kVocabularyMagic)) != 0)
    throw InputError(located(path, 0, "not a builtscene vocabulary file (bad magic)"));
  if (bytes.size() < sizeof(kVocabularyMagic) + 4 + 8) throw InputError(located(path, 0, "truncated vocabulary file (header)"));
  Reader header(bytes, bytes.size(), path);
  char magic[sizeof(kVocabularyMagic)];
  header.raw(magic, sizeof(magic), "magic");
  const auto version = header.get<std::uint32_t>("version");
  if (version != kVocabularyVersion)
    throw InputError(located(path, 0, "vocabulary file version " + std::to_string(version) + " is not supported (expected " +
                                          std::to_string(kVocabularyVersion) + ")"));
  // Checksum before anything else is trusted: flipped bytes anywhere are caught here.
  const std::size_t body = bytes.size() - 8;
  std::uint64_t stored;
  std::memcpy(&stored, bytes.data() + body, 8);
  if (stored != fnv1a64(bytes.data(), body)) throw InputError(located(path, 0, "vocabulary file checksum mismatch (corrupt or truncated)"));

  Reader r(bytes, body, path);
  r.raw(magic, sizeof(magic), "magic");
  r.get<std::uint32_t>("version");
  BowVocabulary voc;
  const auto kind = r.get<std::uint32_t>("kind");
  if (kind > 1) throw InputError(located(path, 0, "field kind: " + std::to_string(kind) + " is neither 0 (binary) nor 1 (float)"));
  voc.kind_ = kind == 0 ? DescriptorKind::kBinary : DescriptorKind::kFloat;
  const auto cols = r.get<std::uint32_t>("cols");
  const auto k = r.get<std::uint32_t>("k");
  const auto levels = r.get<std::uint32_t>("levels");
  const auto node_count = r.get<std::uint32_t>("node_count");
  if (cols == 0 || cols > 4096) throw InputError(located(path, 0, "field cols: " + std::to_string(cols) + " out of range"));
  if (k < 2 || k > 1000) throw InputError(located(path, 0, "field k: " + std::to_string(k) + " out of range"));
  if (levels < 1 || levels > 8) throw InputError(located(path, 0, "field levels: " + std::to_string(levels) + " out of range"));
  const std::size_t elem = voc.kind_ == DescriptorKind::kBinary ? 1 : 4;
  const std::size_t row_bytes = elem * cols;
  if (node_count < 2 || (body - r.position()) != static_cast<std::size_t>(node_count) * (4 + 8 + row_bytes))
    throw InputError(located(path, 0, "field node_count: " + std::to_string(node_count) + " does not match the file size"));
  voc.cols_ = static_cast<int>(cols);
  voc.k_ = static_cast<int>(k);
  voc.levels_ = static_cast<int>(levels);
  voc.nodes_.resize(node_count);
  voc.centres_ = cv::Mat(static_cast<int>(node_count), static_cast<int>(cols), voc.kind_ == DescriptorKind::kBinary ? CV_8U : CV_32F);
  std::vector<int> children(node_count, 0), depth(node_count, 0);
  for (std::uint32_t i = 0; i < node_count; ++i) {
    auto& n = voc.nodes_[i];
    n.parent = r.get<std::int32_t>("node parent");
    n.weight = r.get<double>("node weight");
    r.raw(voc.centres_.ptr(static_cast<int>(i)), row_bytes, "node centre");
    if (i == 0 ? n.parent != -1 : (n.parent < 0 || static_cast<std::uint32_t>(n.parent) >= i))
      throw InputError(located(path, 0, "node " + std::to_string(i) + ": parent " + std::to_string(n.parent) + " invalid"));
    if (!(n.weight >= 0) || !std::isfinite(n.weight))
      throw InputError(located(path, 0, "node " + std::to_string(i) + ": weight is not a finite non-negative number"));
    if (i > 0) {
      const auto p = static_cast<std::size_t>(n.parent);
      depth[i] = depth[p] + 1;
      if (++children[p] > static_cast<int>(k) || depth[i] > static_cast<int>(levels))
        throw InputError(located(path, 0, "node " + std::to_string(i) + ": tree deeper or wider than k and levels allow"));
    }
  }
  voc.index_words();
  return voc;
}

}  // namespace builtscene
