#include "barcode/inventory.hpp"

#include <algorithm>
#include <fstream>
#include <sstream>

#include <opencv2/imgcodecs.hpp>

#include "core/errors.hpp"

namespace builtscene::barcode {
namespace fs = std::filesystem;

void Inventory::add(std::size_t frame, const std::string& code, const std::string& symbology, const cv::Mat& crop) {
  auto [it, inserted] = entries_.try_emplace({code, symbology});
  InventoryEntry& e = it->second;
  if (inserted) {
    e.code = code;
    e.symbology = symbology;
    e.first_frame = frame;
    e.last_frame = frame;
  }
  ++e.reads;
  e.first_frame = std::min(e.first_frame, frame);
  e.last_frame = std::max(e.last_frame, frame);
  if (e.frames.empty() || e.frames.back() != frame) e.frames.push_back(frame);
  if (!crop.empty() && crop.total() > e.best_crop.total()) e.best_crop = crop.clone();
}

std::vector<const InventoryEntry*> Inventory::entries() const {
  std::vector<const InventoryEntry*> v;
  for (const auto& [key, e] : entries_) v.push_back(&e);
  std::stable_sort(v.begin(), v.end(), [](const InventoryEntry* a, const InventoryEntry* b) {
    if (a->first_frame != b->first_frame) return a->first_frame < b->first_frame;
    if (a->code != b->code) return a->code < b->code;
    return a->symbology < b->symbology;
  });
  return v;
}

std::size_t Inventory::total_reads() const {
  std::size_t n = 0;
  for (const auto& [key, e] : entries_) n += e.reads;
  return n;
}

bool Inventory::contains(const std::string& code, const std::string& symbology) const {
  return entries_.count({code, symbology}) > 0;
}

std::string csv_field(const std::string& s) {
  if (s.find_first_of(",\"\n\r") == std::string::npos) return s;
  std::string r = "\"";
  for (char c : s) {
    if (c == '"') r += '"';
    r += c;
  }
  return r + "\"";
}

std::vector<std::string> split_csv_line(const std::string& line) {
  std::vector<std::string> out;
  std::string cur;
  bool quoted = false;
  for (std::size_t i = 0; i < line.size(); ++i) {
    const char c = line[i];
    if (quoted) {
      if (c == '"' && i + 1 < line.size() && line[i + 1] == '"') {
        cur += '"';
        ++i;
      } else if (c == '"') {
        quoted = false;
      } else {
        cur += c;
      }
    } else if (c == '"') {
      quoted = true;
    } else if (c == ',') {
      out.push_back(cur);
      cur.clear();
    } else if (c != '\r') {
      cur += c;
    }
  }
  out.push_back(cur);
  return out;
}

std::string format_frame_ranges(const std::vector<std::size_t>& frames) {
  std::string s;
  for (std::size_t i = 0; i < frames.size();) {
    std::size_t j = i;
    while (j + 1 < frames.size() && frames[j + 1] == frames[j] + 1) ++j;
    if (!s.empty()) s += ';';
    s += std::to_string(frames[i]);
    if (j > i) s += "-" + std::to_string(frames[j]);
    i = j + 1;
  }
  return s;
}

std::vector<std::size_t> parse_frame_ranges(const std::string& text, const std::string& what) {
  std::vector<std::size_t> frames;
  std::stringstream ss(text);
  std::string part;
  while (std::getline(ss, part, ';')) {
    if (part.empty()) continue;
    try {
      const auto dash = part.find('-');
      std::size_t used = 0;
      const std::size_t a = std::stoul(part.substr(0, dash), &used);
      const std::size_t b = dash == std::string::npos ? a : std::stoul(part.substr(dash + 1));
      if (b < a || b - a > 10'000'000) throw std::invalid_argument("range");
      for (std::size_t f = a; f <= b; ++f) frames.push_back(f);
    } catch (const std::exception&) {
      throw InputError(what + ": malformed frame list '" + text + "'");
    }
  }
  return frames;
}

void Inventory::write(const fs::path& dir, const nlohmann::json& extra) const {
  std::error_code ec;
  fs::create_directories(dir / "crops", ec);
  if (ec) throw Failure(located(dir, 0, "cannot create output folder: " + ec.message()));
  const auto list = entries();
  nlohmann::json codes = nlohmann::json::array();
  std::ostringstream csv;
  csv << "code,symbology,reads,first_frame,last_frame,frames,crop\n";
  std::size_t i = 0;
  for (const InventoryEntry* e : list) {
    std::string crop;
    if (!e->best_crop.empty()) {
      crop = "crops/" + std::to_string(i) + ".png";
      cv::imwrite((dir / crop).string(), e->best_crop);
    }
    ++i;
    const std::string ranges = format_frame_ranges(e->frames);
    csv << csv_field(e->code) << ',' << csv_field(e->symbology) << ',' << e->reads << ',' << e->first_frame << ','
        << e->last_frame << ',' << ranges << ',' << crop << '\n';
    codes.push_back({{"code", e->code},
                     {"symbology", e->symbology},
                     {"reads", e->reads},
                     {"first_frame", e->first_frame},
                     {"last_frame", e->last_frame},
                     {"frames", ranges},
                     {"crop", crop}});
  }
  nlohmann::json j = extra.is_object() ? extra : nlohmann::json::object();
  j["codes"] = codes;
  j["distinct_codes"] = list.size();
  j["reads"] = total_reads();
  auto write_atomic = [&](const fs::path& target, const std::string& content) {
    const fs::path tmp = target.string() + ".tmp";
    {
      std::ofstream f(tmp, std::ios::binary);
      f << content;
      if (!f) throw Failure(located(tmp, 0, "cannot write"));
    }
    fs::rename(tmp, target, ec);
    if (ec) throw Failure(located(target, 0, "cannot write: " + ec.message()));
  };
  write_atomic(dir / "inventory.csv", csv.str());
  write_atomic(dir / "inventory.json", j.dump(2) + "\n");
}

Inventory Inventory::read_csv(const fs::path& file) {
  std::ifstream f(file);
  if (!f) throw InputError(located(file, 0, "cannot open inventory"));
  std::string line;
  if (!std::getline(f, line)) throw InputError(located(file, 0, "empty file, expected a header row"));
  const auto header = split_csv_line(line);
  auto col = [&](const std::string& name) -> std::size_t {
    const auto it = std::find(header.begin(), header.end(), name);
    if (it == header.end()) throw InputError(located(file, 1, "missing column '" + name + "'"));
    return static_cast<std::size_t>(it - header.begin());
  };
  const std::size_t c_code = col("code"), c_sym = col("symbology"), c_reads = col("reads"),
                    c_frames = col("frames");
  Inventory inv;
  std::size_t lineno = 1;
  while (std::getline(f, line)) {
    ++lineno;
    if (line.empty() || line == "\r") continue;
    const auto v = split_csv_line(line);
    if (v.size() < header.size()) throw InputError(located(file, lineno, "too few fields"));
    std::size_t reads = 0;
    try {
      reads = std::stoul(v[c_reads]);
    } catch (const std::exception&) {
      throw InputError(located(file, lineno, "field 'reads' is not a number: '" + v[c_reads] + "'"));
    }
    const auto frames = parse_frame_ranges(v[c_frames], located(file, lineno, "field 'frames'"));
    auto& e = inv.entries_[{v[c_code], v[c_sym]}];
    e.code = v[c_code];
    e.symbology = v[c_sym];
    e.reads = reads;
    e.frames = frames;
    e.first_frame = frames.empty() ? 0 : frames.front();
    e.last_frame = frames.empty() ? 0 : frames.back();
  }
  return inv;
}

}  // namespace builtscene::barcode
