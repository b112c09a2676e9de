#pragma once
// Saved maps: a versioned binary file holding everything needed to keep mapping or to
// localize later: keyframes (id, timestamp, pose, keypoints with depth and right coordinate,
// descriptors, their map points, spanning-tree parent), map points (position, normal,
// descriptor, scale range, observations, tracking counters), the covisibility graph and the
// id counters. Bag-of-words vectors are not stored: they are recomputed from the descriptors
// on load by the vocabulary in use, whose checksum the header records so that a map is never
// used with another vocabulary.
//
// Layout (little-endian throughout):
//   header  magic "BSMAP\r\n\x1a" | u32 version | u32 0x01020304 (byte-order check)
//           | u64 vocabulary checksum (0 = none) | u32 section count | u32 reserved
//           | u64 bytes after the header | u32 CRC-32 of the preceding 40 bytes | u32 reserved
//   section u32 tag | u32 CRC-32 of the payload | u64 payload size | payload
// Sections, in this order: "CTXT" (camera, pyramid, descriptor kind, id counters),
// "KFRM" (keyframes), "MPTS" (map points), "COVI" (covisibility edges), "LOOP" (loop edges:
// u32 count, then pairs of i64 keyframe ids, smaller id first; since version 2), "DLNK"
// (depth links of `slam --depth-links`: u32 count, then per link i64 keyframe id, i64 id of
// the keyframe it is aligned to, the relative pose as quaternion w x y z and translation,
// and the upper triangle of its 6 x 6 information row by row, 21 doubles; since version 3),
// "PLAN" (plane landmarks, plane_landmark.hpp: i64 next plane id; u32 count, then per map
// plane by id i64 id, normal n_w (3 doubles, unit), offset d_w, last_seen_from (3 doubles),
// u32 observer count and the observers' i64 keyframe ids in the order they joined; then u32
// count of keyframes with measured planes, each i64 keyframe id, u32 count and per measurement
// n_c (3 doubles, unit), d_c, u64 inliers, i64 map plane id or -1; since version 4).
// Records are sorted by id and maps by key, so save -> load -> save gives identical bytes.
// Version 1 files (without LOOP) are read as maps without loop edges, version 2 files
// (without DLNK) as maps without depth links, version 3 files (without PLAN) as maps without
// planes; newer versions are rejected.
//
// Reading validates before it builds: checksums, sizes, every id reference and index; any
// problem is an InputError "FILE: what is wrong" and the target map is left untouched.
#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "slam/frame.hpp"

namespace builtscene::slam {

class Map;

inline constexpr std::uint32_t kMapFileVersion = 4;

struct MapFileInfo {
  std::uint32_t version = 0;
  std::uint64_t vocabulary_checksum = 0;
  std::size_t keyframes = 0;
  std::size_t points = 0;
  std::size_t bytes = 0;
};

// The map as file bytes. The caller holds map.mutex().
std::vector<std::uint8_t> encode_map(const Map& map, const FrameContext& ctx, std::uint64_t vocabulary_checksum);

// Replaces the content of `map` by the decoded one (keyframes get `ctx`; the file's camera,
// pyramid and descriptor kind must match it). `name` labels errors. With a vocabulary
// checksum given, a map saved with another non-zero checksum is rejected. The caller holds
// map.mutex().
MapFileInfo decode_map(const std::uint8_t* data, std::size_t size, const std::string& name, Map& map,
                       const std::shared_ptr<const FrameContext>& ctx,
                       std::optional<std::uint64_t> vocabulary_checksum = std::nullopt);

// File wrappers: writing goes through a temporary file renamed into place, so a failed save
// never leaves half a map behind. Both take the map lock themselves.
MapFileInfo write_map_file(const std::filesystem::path& path, const Map& map, const FrameContext& ctx,
                           std::uint64_t vocabulary_checksum = 0);
MapFileInfo read_map_file(const std::filesystem::path& path, Map& map, const std::shared_ptr<const FrameContext>& ctx,
                          std::optional<std::uint64_t> vocabulary_checksum = std::nullopt);

// CRC-32 (zlib's polynomial) of a byte range.
std::uint32_t map_file_crc32(const std::uint8_t* data, std::size_t size);

}  // namespace builtscene::slam
