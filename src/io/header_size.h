// header_size.h: how many pixels an image header may claim, so that memory follows the
// file and not the header.
//
// Every reader sizes its buffers from the width and height in the header. A damaged header
// (a 1.2 MB frame whose data window says 20000x20000) would have hbil allocate tens of
// gigabytes before a single pixel fails to decode. check_header_size() runs on every header
// before anything is allocated from it and refuses, as Error(Exit::input) naming the file:
//
//  - more than kMaxPixels pixels, hbil's stated limit (2^28: 16384 x 16384, 32 times a
//    4K UHD frame);
//  - an OpenEXR header whose pixels could not be stored in the file's bytes. An OpenEXR
//    file holds, per chunk (a block of scanlines or a tile), an 8-byte entry of the offset
//    table and a chunk header (8 bytes for scanlines: y and size; 20 for tiles), and the
//    chunk's data, which a compression can make at most R times smaller than the raw
//    pixel bytes: exr_max_compression_ratio() gives R for each, from how the codec works.
//    A header claiming more than (file size − chunk overhead) × R raw bytes is damaged.
//
// The bounds are maxima no real file reaches (a constant image compresses far less than
// deflate's limit), so no valid file is refused by them.
#pragma once

#include <OpenImageIO/imageio.h>

#include <cstddef>
#include <memory>
#include <string>

namespace hbil::io {

inline constexpr size_t kMaxPixels = size_t(1) << 28;

// The largest ratio of raw pixel bytes to stored bytes an OpenEXR compression can reach
// ("zip", "dwaa:45", ... as OpenImageIO names them); 0 for a name it does not know.
double exr_max_compression_ratio(const std::string& compression);

// Scanlines per chunk of an OpenEXR compression (256, the largest, for an unknown one).
int exr_lines_per_chunk(const std::string& compression);

// Throws Error(Exit::input, "<where>: ...") when the header claims more pixels than the
// limit, or (openexr) more than `file_bytes` bytes of an OpenEXR file can hold.
// `file_bytes` 0: not known, only the limit is checked.
void check_header_size(const OIIO::ImageSpec& spec, bool openexr, size_t file_bytes,
                       const std::string& where);

// The same for the file at `path` (its size read here).
void check_header_size(const std::string& path, const OIIO::ImageSpec& spec, bool openexr,
                       const std::string& where);

// OpenImageIO's ImageInput::open(path), after check_exr_attributes(path, where).
std::unique_ptr<OIIO::ImageInput> open_image_input(const std::string& path,
                                                   const std::string& where);

// For an OpenEXR file (by its magic number; other files pass): walks its header(s) and
// throws Error(Exit::input, "<where>: ...") when an attribute claims more bytes than the
// file holds after it (OpenEXR sizes an attribute's buffer from that claim before reading
// it, so a damaged 20 KB file could make it fill 2 GB), or a channel whose pixel type is
// not uint, half or float (OpenImageIO aborts on one) or whose sampling is below 1; and runs
// check_header_size() on each header's dataWindow, channels, compression and tiles, since
// OpenEXR sizes its line buffers from them when the file is opened. Other damage is left to
// the reader.
void check_exr_attributes(const std::string& path, const std::string& where);

}  // namespace hbil::io
