#include "synth/png_writer.hpp"

#include <cstdint>
#include <cstring>
#include <fstream>
#include <stdexcept>
#include <vector>

#include <zlib.h>

namespace builtscene::synth {
namespace {

void put32(std::string& s, std::uint32_t v) {
  s += static_cast<char>(v >> 24);
  s += static_cast<char>(v >> 16);
  s += static_cast<char>(v >> 8);
  s += static_cast<char>(v);
}

void chunk(std::string& out, const char* type, const unsigned char* data, std::size_t n) {
  put32(out, static_cast<std::uint32_t>(n));
  const std::size_t start = out.size();
  out.append(type, 4);
  out.append(reinterpret_cast<const char*>(data), n);
  const uLong crc = crc32(0L, reinterpret_cast<const Bytef*>(out.data() + start), static_cast<uInt>(n + 4));
  put32(out, static_cast<std::uint32_t>(crc));
}

}  // namespace

std::string encode_png_fast(const cv::Mat& img) {
  int bpp, color_type, depth_bits;
  if (img.type() == CV_8UC3) {
    bpp = 3, color_type = 2, depth_bits = 8;
  } else if (img.type() == CV_8U) {
    bpp = 1, color_type = 0, depth_bits = 8;
  } else if (img.type() == CV_16U) {
    bpp = 2, color_type = 0, depth_bits = 16;
  } else {
    throw std::invalid_argument("encode_png_fast: unsupported image type");
  }
  const int W = img.cols, H = img.rows;
  const std::size_t row_bytes = static_cast<std::size_t>(W) * bpp;
  // Raw scanlines with the Sub filter (each byte minus the byte bpp to its left).
  std::vector<unsigned char> raw((row_bytes + 1) * H);
  std::vector<unsigned char> line(row_bytes);
  for (int y = 0; y < H; ++y) {
    const unsigned char* src = img.ptr<unsigned char>(y);
    if (img.type() == CV_8UC3) {
      for (int x = 0; x < W; ++x) {
        line[3 * x] = src[3 * x + 2];
        line[3 * x + 1] = src[3 * x + 1];
        line[3 * x + 2] = src[3 * x];
      }
    } else if (img.type() == CV_16U) {
      const std::uint16_t* s16 = img.ptr<std::uint16_t>(y);
      for (int x = 0; x < W; ++x) {
        line[2 * x] = static_cast<unsigned char>(s16[x] >> 8);  // PNG is big-endian
        line[2 * x + 1] = static_cast<unsigned char>(s16[x] & 255);
      }
    } else {
      std::memcpy(line.data(), src, row_bytes);
    }
    unsigned char* dst = &raw[(row_bytes + 1) * y];
    dst[0] = 1;  // filter type Sub
    for (std::size_t i = 0; i < row_bytes; ++i)
      dst[1 + i] = static_cast<unsigned char>(line[i] - (i >= static_cast<std::size_t>(bpp) ? line[i - bpp] : 0));
  }
  // Run-length-only deflate: long runs (no-reading depth, flat paint) shrink, the Huffman
  // stage does the rest; no costly match search on sensor noise.
  z_stream zs{};
  if (deflateInit2(&zs, 1, Z_DEFLATED, 15, 8, Z_RLE) != Z_OK) throw std::runtime_error("deflateInit2 failed");
  std::vector<unsigned char> comp(deflateBound(&zs, static_cast<uLong>(raw.size())));
  zs.next_in = raw.data();
  zs.avail_in = static_cast<uInt>(raw.size());
  zs.next_out = comp.data();
  zs.avail_out = static_cast<uInt>(comp.size());
  const int rc = deflate(&zs, Z_FINISH);
  const std::size_t comp_size = comp.size() - zs.avail_out;
  deflateEnd(&zs);
  if (rc != Z_STREAM_END) throw std::runtime_error("deflate failed");

  std::string out("\x89PNG\r\n\x1a\n", 8);
  unsigned char ihdr[13];
  const std::uint32_t w = static_cast<std::uint32_t>(W), h = static_cast<std::uint32_t>(H);
  for (int i = 0; i < 4; ++i) {
    ihdr[i] = static_cast<unsigned char>(w >> (24 - 8 * i));
    ihdr[4 + i] = static_cast<unsigned char>(h >> (24 - 8 * i));
  }
  ihdr[8] = static_cast<unsigned char>(depth_bits);
  ihdr[9] = static_cast<unsigned char>(color_type);
  ihdr[10] = ihdr[11] = ihdr[12] = 0;
  chunk(out, "IHDR", ihdr, 13);
  chunk(out, "IDAT", comp.data(), comp_size);
  chunk(out, "IEND", nullptr, 0);
  return out;
}

bool write_png_fast(const std::filesystem::path& path, const cv::Mat& image) {
  const std::string data = encode_png_fast(image);
  std::ofstream f(path, std::ios::binary);
  f.write(data.data(), static_cast<std::streamsize>(data.size()));
  return static_cast<bool>(f);
}

}  // namespace builtscene::synth
