// exr_deflate.h: a faster reader for the OpenEXR layout renderers write most: scanlines
// compressed with ZIP or ZIPS (Blender's default), or not compressed.
//
// OpenEXR 3.1 inflates with zlib, which takes most of a frame's read time (a 1920x1080
// Blender file of 34 channels: 0.6 of 0.85 CPU-s). libdeflate inflates the same blocks 2.7x
// faster. Each block's bytes are fetched through OpenEXR (rawPixelData, which also checks
// the block's place in the file), inflated, their predictor undone, and only the channels
// asked for are converted, straight from the split byte halves the ZIP format stores.
// The values are those OpenEXR's readPixels gives, bit for bit (half and uint converted to
// float as OpenEXR converts them), for any thread count.
#pragma once

#include <OpenEXR/ImfInputFile.h>

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace hbil::io {

// One channel to convert: the sample at (x, y) of the data window, counted from its corner,
// goes to dst[(y * width + x) * stride].
// With `half` set, a HALF channel's samples are stored there as they are (their bits), in
// place of dst.
struct ExrChannelTarget {
  std::string name;
  float* dst;
  size_t stride;
  std::uint16_t* half = nullptr;
};

// Reads the targets' channels of a scanline file compressed with ZIP, ZIPS or nothing, with
// no subsampled channel. Returns false, having read nothing, for any other layout (tiled,
// deep, another compression, a target not in the file): the caller then reads through
// OpenEXR. Throws std::runtime_error naming the rows of a damaged block.
bool read_deflate_scanlines(Imf::InputFile& file, const std::vector<ExrChannelTarget>& targets);

}  // namespace hbil::io
