// header_size.cpp: see header_size.h.
#include "io/header_size.h"

#include <algorithm>
#include <climits>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <sstream>

#include "hbil/error.h"

namespace hbil::io {

namespace {

// "dwaa:45" -> "dwaa".
std::string codec(const std::string& compression) {
  return compression.substr(0, compression.find(':'));
}

// deflate (zlib) cannot do better than 1032:1: its longest match, 258 bytes, costs at
// least 2 bits.
constexpr double kDeflate = 1032;

}  // namespace

double exr_max_compression_ratio(const std::string& compression) {
  const std::string c = codec(compression);
  if (c == "none") return 1;
  // A run of up to 128 equal bytes is stored as 2 (count, value).
  if (c == "rle") return 64;
  if (c == "zip" || c == "zips") return kDeflate;
  // Floats cut to 24 bits, then deflated.
  if (c == "pxr24") return kDeflate * 4 / 3;
  // Wavelet, then Huffman with run-length codes: a run of at most 256 16-bit values costs
  // the value's code, the run code (1 bit each at least) and an 8-bit count.
  if (c == "piz") return 256.0 * 16 / 10;
  // A 4x4 block of halves (32 bytes) in 14 bytes, or 3 when flat (b44a); floats stay raw.
  if (c == "b44") return 32.0 / 14;
  if (c == "b44a") return 32.0 / 3;
  // An 8x8 block of a lossy channel (128 bytes) becomes at least its DC and an end-of-block
  // code (4 bytes), and the other channels are run-length coded (at most 64:1); either
  // stream is then deflated.
  if (c == "dwaa" || c == "dwab") return 64 * kDeflate;
  return 0;
}

int exr_lines_per_chunk(const std::string& compression) {
  const std::string c = codec(compression);
  if (c == "none" || c == "rle" || c == "zips") return 1;
  if (c == "zip" || c == "pxr24") return 16;
  if (c == "piz" || c == "b44" || c == "b44a" || c == "dwaa") return 32;
  return 256;  // dwab, and the most any compression uses
}

void check_header_size(const OIIO::ImageSpec& spec, bool openexr, size_t file_bytes,
                       const std::string& where) {
  const uint64_t w = uint64_t(std::max(spec.width, 0)), h = uint64_t(std::max(spec.height, 0)),
                 d = uint64_t(std::max(spec.depth, 1));
  const uint64_t pixels = w * h * d;  // each below 2^31: no overflow
  std::ostringstream claim;
  claim << where << ": the header claims " << spec.width << "x" << spec.height;
  if (d > 1) claim << "x" << d;
  claim << " pixels";
  if (pixels > kMaxPixels) {
    claim << ", more than hbil's limit of " << kMaxPixels << " (16384x16384)";
    throw Error(Exit::input, claim.str());
  }
  if (!openexr || file_bytes == 0) return;
  uint64_t pixel_bytes = 0;
  for (int c = 0; c < spec.nchannels; ++c) pixel_bytes += spec.channelformat(c).size();
  const std::string compression = spec.get_string_attribute("compression", "none");
  // Chunks: tiles of the first level, or blocks of scanlines.
  uint64_t chunks, chunk_header;
  if (spec.tile_width > 0 && spec.tile_height > 0) {
    chunks = (w + spec.tile_width - 1) / spec.tile_width *
             ((h + spec.tile_height - 1) / spec.tile_height);
    chunk_header = 20;  // tile x, y, level x, y, data size
  } else {
    const uint64_t lines = uint64_t(exr_lines_per_chunk(compression));
    chunks = (h + lines - 1) / lines;
    chunk_header = 8;  // y, data size
  }
  const uint64_t overhead = chunks * (8 + chunk_header);  // with the offset table's entry
  const double ratio = exr_max_compression_ratio(compression);
  const double raw = double(pixels) * double(pixel_bytes);
  const bool too_many_chunks = overhead > file_bytes;
  const bool too_much_data =
      ratio > 0 &&
      raw > (double(file_bytes) - double(std::min<uint64_t>(overhead, file_bytes))) * ratio;
  if (!too_many_chunks && !too_much_data) return;
  claim << " of " << spec.nchannels << " channels (" << uint64_t(raw) << " bytes uncompressed, "
        << chunks << " chunks), more than " << compression << " compression can store in the "
        << file_bytes << " bytes of the file: the header is damaged";
  throw Error(Exit::input, claim.str());
}

void check_header_size(const std::string& path, const OIIO::ImageSpec& spec, bool openexr,
                       const std::string& where) {
  std::error_code ec;
  const uintmax_t bytes = std::filesystem::file_size(path, ec);
  check_header_size(spec, openexr, ec ? 0 : size_t(bytes), where);
}

std::unique_ptr<OIIO::ImageInput> open_image_input(const std::string& path,
                                                   const std::string& where) {
  check_exr_attributes(path, where);
  return OIIO::ImageInput::open(path);
}

namespace {

// The little-endian int32 at p (OpenEXR's byte order).
int32_t le_int32(const char* p) {
  const auto b = [p](int k) { return uint32_t(uint8_t(p[k])); };
  return int32_t(b(0) | b(1) << 8 | b(2) << 16 | b(3) << 24);
}

// What the size check needs of one OpenEXR header, from its attributes.
struct ExrHeaderFacts {
  bool window = false;
  int64_t width = 0, height = 0;  // dataWindow
  std::vector<OIIO::TypeDesc> formats;
  std::string compression = "none";
  int tile_width = 0, tile_height = 0;
};

// A channel list (OpenEXR "chlist"): per channel a name, the pixel type (int32: 0 uint,
// 1 half, 2 float), pLinear and 3 reserved bytes, x and y sampling (int32), then an empty
// name. OpenImageIO aborts the process on another pixel type, and a sampling below 1
// divides by zero: both are refused here. So is a list that does not end within the
// attribute's size (OpenEXR reads on into the next attribute's bytes, and takes its pixel
// types from there), or that ends before it.
void read_channel_list(const std::string& list, ExrHeaderFacts& facts, const std::string& where) {
  facts.formats.clear();  // of two lists, the last counts (as in OpenEXR)
  size_t at = 0;
  for (; at < list.size() && list[at] != '\0';) {
    const size_t end = list.find('\0', at);
    if (end == std::string::npos || end + 17 > list.size())
      throw Error(Exit::input,
                  where + ": damaged OpenEXR header: the channel list ends inside channel \"" +
                      list.substr(at, std::min(end, list.size()) - at) + "\"");
    const std::string name = list.substr(at, end - at);
    const int32_t type = le_int32(&list[end + 1]), xs = le_int32(&list[end + 9]),
                  ys = le_int32(&list[end + 13]);
    if (type < 0 || type > 2)
      throw Error(Exit::input, where + ": damaged OpenEXR header: channel \"" + name +
                                   "\" has pixel type " + std::to_string(type) +
                                   " (0 uint, 1 half and 2 float are defined)");
    if (xs < 1 || ys < 1)
      throw Error(Exit::input, where + ": damaged OpenEXR header: channel \"" + name +
                                   "\" has sampling " + std::to_string(xs) + "x" +
                                   std::to_string(ys) + " (at least 1x1)");
    facts.formats.push_back(type == 1   ? OIIO::TypeDesc::HALF
                            : type == 2 ? OIIO::TypeDesc::FLOAT
                                        : OIIO::TypeDesc::UINT32);
    at = end + 17;
  }
  if (at >= list.size())
    throw Error(Exit::input,
                where + ": damaged OpenEXR header: the channel list has no end within its size");
  // OpenEXR reads the list up to its end and goes on from there, whatever size the attribute
  // claims: a list that ends before its size puts it out of step with this walk, which then
  // missed a dataWindow that OpenEXR read (found by tests/fuzz/fuzz_povray).
  if (at + 1 != list.size())
    throw Error(Exit::input, where + ": damaged OpenEXR header: the channel list ends " +
                                 std::to_string(list.size() - at - 1) +
                                 " bytes before its attribute's size");
}

// Takes the attributes the size check needs from their value bytes.
void note_attribute(const std::string& name, const std::string& type, const std::string& value,
                    ExrHeaderFacts& facts, const std::string& where) {
  static const char* const kCompressions[] = {"none",  "rle", "zips", "zip",  "piz",
                                              "pxr24", "b44", "b44a", "dwaa", "dwab"};
  if (type == "chlist") {
    read_channel_list(value, facts, where);
  } else if (name == "dataWindow" && type == "box2i" && value.size() == 16) {
    facts.window = true;
    facts.width = int64_t(le_int32(&value[8])) - le_int32(&value[0]) + 1;
    facts.height = int64_t(le_int32(&value[12])) - le_int32(&value[4]) + 1;
  } else if (name == "compression" && type == "compression" && value.size() == 1) {
    const unsigned c = uint8_t(value[0]);
    facts.compression = c < std::size(kCompressions) ? kCompressions[c] : "unknown";
  } else if (name == "tiles" && type == "tiledesc" && value.size() == 9) {
    facts.tile_width = std::max(0, le_int32(&value[0]));
    facts.tile_height = std::max(0, le_int32(&value[4]));
  }
}

// The size of a value of one of OpenEXR's fixed-size attribute types; 0 for the others
// (string, chlist, preview, vectors, and types OpenEXR does not know, which it keeps opaque
// at their claimed size).
int fixed_size(const std::string& type) {
  static const std::pair<const char*, int> kSizes[] = {{"int", 4},
                                                       {"float", 4},
                                                       {"double", 8},
                                                       {"box2i", 16},
                                                       {"box2f", 16},
                                                       {"v2i", 8},
                                                       {"v2f", 8},
                                                       {"v2d", 16},
                                                       {"v3i", 12},
                                                       {"v3f", 12},
                                                       {"v3d", 24},
                                                       {"m33f", 36},
                                                       {"m33d", 72},
                                                       {"m44f", 64},
                                                       {"m44d", 128},
                                                       {"compression", 1},
                                                       {"lineOrder", 1},
                                                       {"envmap", 1},
                                                       {"deepImageState", 1},
                                                       {"tiledesc", 9},
                                                       {"chromaticities", 32},
                                                       {"keycode", 28},
                                                       {"timecode", 8},
                                                       {"rational", 8}};
  for (const auto& [name, size] : kSizes)
    if (type == name) return size;
  return 0;
}

// check_header_size() on what the attributes of one header claim, before any library sizes
// a buffer from them.
void check_facts(const ExrHeaderFacts& facts, size_t file_bytes, const std::string& where) {
  if (!facts.window || facts.width <= 0 || facts.height <= 0) return;  // the reader's to report
  if (facts.width > INT32_MAX || facts.height > INT32_MAX)
    throw Error(Exit::input, where + ": the header claims " + std::to_string(facts.width) + "x" +
                                 std::to_string(facts.height) + " pixels: the header is damaged");
  OIIO::ImageSpec spec(int(facts.width), int(facts.height), int(facts.formats.size()),
                       OIIO::TypeDesc::HALF);
  spec.channelformats = facts.formats;
  spec.tile_width = facts.tile_width;
  spec.tile_height = facts.tile_height;
  spec.attribute("compression", facts.compression);
  check_header_size(spec, true, file_bytes, where);
}

}  // namespace

void check_exr_attributes(const std::string& path, const std::string& where) {
  std::ifstream in(path, std::ios::binary);
  unsigned char head[8];
  if (!in.read(reinterpret_cast<char*>(head), 8)) return;
  if (head[0] != 0x76 || head[1] != 0x2f || head[2] != 0x31 || head[3] != 0x01) return;
  std::error_code ec;
  const auto size = std::filesystem::file_size(path, ec);
  if (ec) return;
  const bool multipart = (head[5] & 0x10) != 0;  // version flags, bit 12
  // A null-terminated name of at most 255 characters; false at the end of the file. A longer
  // one is damage: past it, where OpenEXR goes on reading is not where this walk would.
  auto read_name = [&](std::string& name) {
    name.clear();
    for (char c; in.get(c);) {
      if (c == 0) return true;
      if (name.size() == 255)
        throw Error(Exit::input, where +
                                     ": damaged OpenEXR header: a name of more than 255 "
                                     "characters (\"" +
                                     name.substr(0, 40) + "...\")");
      name += c;
    }
    return false;
  };
  std::string name, type, value;
  for (;;) {
    ExrHeaderFacts facts;
    for (;;) {  // one header: attributes up to an empty name
      if (!read_name(name)) return;
      if (name.empty()) break;
      char b[4];
      if (!read_name(type) || !in.read(b, 4)) return;
      const int64_t claimed = le_int32(b);
      const int64_t left = int64_t(size) - int64_t(in.tellg());
      if (claimed < 0 || claimed > left)
        throw Error(Exit::input, where + ": damaged OpenEXR header: attribute \"" + name + "\" (" +
                                     type + ") claims " + std::to_string(claimed) + " bytes, " +
                                     std::to_string(left) + " are left in the file");
      // OpenEXR reads a value of a fixed-size type by its type, whatever size it claims, and
      // then goes on from there: any other size would put it out of step with this walk.
      if (const int natural = fixed_size(type); natural > 0 && claimed != natural)
        throw Error(Exit::input, where + ": damaged OpenEXR header: attribute \"" + name + "\" (" +
                                     type + ") claims " + std::to_string(claimed) +
                                     " bytes, its type has " + std::to_string(natural));
      if (type == "chlist" || type == "box2i" || type == "compression" || type == "tiledesc") {
        value.resize(size_t(claimed));
        if (!in.read(value.data(), claimed)) return;
        note_attribute(name, type, value, facts, where);
      } else {
        in.seekg(claimed, std::ios::cur);
      }
    }
    check_facts(facts, size_t(size), where);
    // Single part: one header. Multi-part: headers until an empty one.
    if (!multipart || in.peek() == 0 || !in) return;
  }
}

}  // namespace hbil::io
