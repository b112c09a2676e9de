#pragma once
// The inventory of a scan: every distinct code (text + symbology) with its reads, first and last
// frame, the frames it was read in and the best crop. Written as inventory.csv, inventory.json
// and crops/*.png; read back from the CSV for evaluation.
#include <cstddef>
#include <filesystem>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>

namespace builtscene::barcode {

struct InventoryEntry {
  std::string code;
  std::string symbology;
  std::size_t reads = 0;
  std::size_t first_frame = 0;
  std::size_t last_frame = 0;
  std::vector<std::size_t> frames;  // distinct, ascending when reads are added in frame order
  cv::Mat best_crop;                // the largest crop it was read from (first one on ties)
  std::string crop_file;            // relative to the output folder, once written
};

class Inventory {
 public:
  // One read of `code` in `frame`; `crop` may be empty.
  void add(std::size_t frame, const std::string& code, const std::string& symbology, const cv::Mat& crop);

  // Entries ordered by first frame, then code: the order a viewer of the video meets them.
  std::vector<const InventoryEntry*> entries() const;
  std::size_t size() const { return entries_.size(); }
  std::size_t total_reads() const;
  bool contains(const std::string& code, const std::string& symbology) const;

  // inventory.csv, inventory.json (`extra` is merged into the JSON's top level) and crops/.
  // Writes to temporary names and renames, so a reader never sees a half-written file.
  void write(const std::filesystem::path& dir, const nlohmann::json& extra = {}) const;

  // Reads inventory.csv (code, symbology, reads, first_frame, last_frame, frames, ...).
  static Inventory read_csv(const std::filesystem::path& file);

 private:
  std::map<std::pair<std::string, std::string>, InventoryEntry> entries_;
};

// "3-7;12;20-21" for {3,4,5,6,7,12,20,21}, and back. parse_frame_ranges throws InputError
// (naming `what`) on malformed text.
std::string format_frame_ranges(const std::vector<std::size_t>& frames);
std::vector<std::size_t> parse_frame_ranges(const std::string& text, const std::string& what);

// Minimal CSV helpers shared by the inventory and truth files.
std::string csv_field(const std::string& s);
std::vector<std::string> split_csv_line(const std::string& line);

}  // namespace builtscene::barcode
