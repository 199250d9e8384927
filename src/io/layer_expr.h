// layer_expr.h: layers of an image, layer expressions over them, and the comparison of one
// image's expression with another's over the valid pixels: the accuracy measure that
// `hbil compare`, `hbil bench` and the tests share.
//
// A layer L of an image is the channel named L, else its channels <L>.<comp>, else
// <prefix>.<L>.<comp> (Blender's view-layer prefix), ordered R G B A X Y Z W.
//
// Layer expressions combine layers per channel with * and + and parentheses:
//
//   sum     := product ('+' product)*
//   product := operand ('*' operand)*
//   operand := NAME | '(' sum ')'
//
// A NAME is any text without + * ( ), spaces around it dropped. Operands have the same
// number of channels, or 1 (used for every channel); channel k of the result is the
// arithmetic of channel k of each operand. Cycles writes no indirect-diffuse layer: the
// reference for hbil's `indirect` is DiffCol*DiffInd, for a composite
// DiffCol*(DiffDir+DiffInd)+Emit.
#pragma once

#include <OpenImageIO/imageio.h>

#include <map>
#include <memory>
#include <string>
#include <vector>

#include "hbil/error_stats.h"

namespace hbil::io {

// Named float channels of one image: a file, or a frame held in memory.
class ChannelSource {
 public:
  virtual ~ChannelSource() = default;
  // The file's path, or what the frame is (for messages).
  virtual const std::string& name() const = 0;
  virtual int width() const = 0;
  virtual int height() const = 0;
  // The origin of the pixels (an EXR's data window), in the display window's raster.
  virtual int x() const { return 0; }
  virtual int y() const { return 0; }
  virtual const std::vector<std::string>& channel_names() const = 0;
  // Channel c, width() * height() values in row order. Throws Error(Exit::input).
  virtual std::vector<float> read(int c) = 0;
};

// An image file read through OpenImageIO, one channel at a time; a scanline EXR compressed
// with ZIP, ZIPS or nothing through exr_deflate.h instead (the same values, several times
// faster).
class ImageFile : public ChannelSource {
 public:
  // Throws Error(Exit::input) naming the file.
  explicit ImageFile(std::string path);
  const std::string& name() const override { return path_; }
  int width() const override { return spec_.width; }
  int height() const override { return spec_.height; }
  int x() const override { return spec_.x; }
  int y() const override { return spec_.y; }
  const std::vector<std::string>& channel_names() const override { return spec_.channelnames; }
  std::vector<float> read(int c) override;
  // Channels [begin, end) in one pass over the file, interleaved: pixel i's channel c at
  // [i * (end − begin) + c − begin]. Throws Error(Exit::input).
  std::vector<float> read_range(int begin, int end);
  const OIIO::ImageSpec& spec() const { return spec_; }

 private:
  // Channels [begin, end) interleaved into dst through exr_deflate.h; false (nothing read) where
  // the file is not of its layout.
  bool read_deflate(int begin, int end, float* dst) const;
  std::string path_;
  OIIO::ImageSpec spec_;
  std::unique_ptr<OIIO::ImageInput> in_;
};

// Channels held in memory: channel c at src[c][i * stride[c]] (null src: 1 everywhere).
class MemoryChannels : public ChannelSource {
 public:
  struct Channel {
    std::string name;
    const float* src = nullptr;
    size_t stride = 1;
  };
  MemoryChannels(std::string name, int width, int height, std::vector<Channel> channels, int x = 0,
                 int y = 0);
  const std::string& name() const override { return name_; }
  int width() const override { return width_; }
  int height() const override { return height_; }
  int x() const override { return x_; }
  int y() const override { return y_; }
  const std::vector<std::string>& channel_names() const override { return names_; }
  std::vector<float> read(int c) override;

 private:
  std::string name_;
  int width_, height_, x_, y_;
  std::vector<Channel> channels_;
  std::vector<std::string> names_;
};

// The channels of layer `layer`. Throws Error(Exit::missing_pass) naming the image.
std::vector<int> layer_channels(const ChannelSource& im, const std::string& layer);

struct LayerExpr {
  enum Op { layer, add, mul } op = layer;
  std::string name;             // op == layer
  std::vector<LayerExpr> args;  // op == add, mul: two or more
};

// `option` (--layer, --ref, ...) names the expression in messages. Throws
// Error(Exit::usage) naming the expression and the character where it fails.
LayerExpr parse_layer_expr(const std::string& option, const std::string& text);
// The expression in its shortest form: no spaces, parentheses only around a sum in a product.
std::string to_string(const LayerExpr& e);

// An expression bound to one image: the result's channels, evaluated one at a time, each
// image channel read once and kept only while a later use is still to come.
class BoundExpr {
 public:
  // Throws Error(Exit::missing_pass) for an absent layer, Error(Exit::usage) for operands
  // whose channel counts do not match; `option` and `text` name the expression.
  BoundExpr(const LayerExpr& e, ChannelSource& im, const std::string& option,
            const std::string& text);
  ~BoundExpr();
  BoundExpr(BoundExpr&&) noexcept;
  size_t channels() const;
  // "AO.R" for a plain layer, "(DiffCol*DiffInd).R" for an expression.
  std::string channel_name(size_t k) const;
  // Channel k of the result (k < n, where n is the count given to prepare()).
  std::vector<float> channel(size_t k);
  // Channels 0..n-1 will be asked for, each once (a 1-channel result serves every k).
  void prepare(size_t n);

  struct Node;  // the bound tree (layer_expr.cpp)

 private:
  std::unique_ptr<Node> root_;
  ChannelSource* im_;
  std::map<int, int> uses_;
  std::map<int, std::vector<float>> cache_;
  std::vector<float> evaluate(const Node& b, size_t k);
  std::vector<float> get(int c);
};

// Which pixels count. "none": all; "auto": the reference's front depth below
// `background_depth`, else its alpha above 0, else all; any other text: the channel of that
// name (in the reference, else in the test) is non-zero.
struct MaskSpec {
  std::string mask = "auto";
  double background_depth = 1e9;
};

// The valid pixels of a comparison; `described` says how they were chosen.
std::vector<unsigned char> make_mask(ChannelSource& test, ChannelSource& ref, const MaskSpec& m,
                                     std::string& described);

struct ChannelError {
  std::string test, reference;  // channel names
  ErrorStats stats;
};

struct LayerComparison {
  std::vector<ChannelError> channels;
  ErrorStats overall;
  std::string mask;  // as make_mask describes it
  // With keep_planes: the channels compared (as in `channels`) and the valid pixels.
  std::vector<std::vector<float>> test_planes, ref_planes;
  std::vector<unsigned char> valid;
};

// An expression of `test` against one of `ref` (one channel against several is compared with
// each: ao.Y against AO.R, AO.G, AO.B). `colour_only`: channel pairs where either channel is
// an alpha (its name ends in ".A" or is "A") are left out, so that a composite is judged on
// R, G, B. `region`, when given, keeps only the valid pixels where it is non-zero.
// `keep_planes`: the result keeps the compared channels and the valid pixels. Images whose
// pixels lie at different places (data windows) are compared over the reference's, which
// must lie within the test's (an overscan's output against a render of the frame alone).
// Throws Error(Exit::bad_data) for images that do not overlap so, Error(Exit::usage) for
// channel counts that do not match.
LayerComparison compare_layers(ChannelSource& test, const LayerExpr& test_expr,
                               const std::string& test_option, const std::string& test_text,
                               ChannelSource& ref, const LayerExpr& ref_expr,
                               const std::string& ref_option, const std::string& ref_text,
                               const MaskSpec& mask, bool colour_only = false,
                               const std::vector<unsigned char>* region = nullptr,
                               bool keep_planes = false);

}  // namespace hbil::io
