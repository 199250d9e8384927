// layer_expr.cpp: see layer_expr.h.
#include "io/layer_expr.h"

#include <OpenEXR/ImfHeader.h>
#include <OpenEXR/ImfInputFile.h>
#include <OpenEXR/ImfThreading.h>

#include <algorithm>
#include <cctype>
#include <functional>
#include <string_view>

#include "hbil/error.h"
#include "io/exr_deflate.h"
#include "io/header_size.h"

namespace hbil::io {

ImageFile::ImageFile(std::string path) : path_(std::move(path)) {
  in_ = open_image_input(path_, path_);
  if (!in_) throw Error(Exit::input, path_ + ": cannot read: " + OIIO::geterror());
  spec_ = in_->spec();
  check_header_size(path_, spec_, std::string(in_->format_name()) == "openexr", path_);
}

bool ImageFile::read_deflate(int begin, int end, float* dst) const {
  if (std::string(in_->format_name()) != "openexr") return false;
  // OpenImageIO reads an integer channel as a fraction of its range, OpenEXR as its value.
  for (int c = begin; c < end; ++c)
    if (spec_.channelformat(c).basetype != OIIO::TypeDesc::HALF &&
        spec_.channelformat(c).basetype != OIIO::TypeDesc::FLOAT)
      return false;
  try {
    Imf::InputFile file(path_.c_str(), Imf::globalThreadCount());
    const Imath::Box2i dw = file.header().dataWindow();
    if (dw.min.x != spec_.x || dw.min.y != spec_.y || dw.max.x - dw.min.x + 1 != spec_.width ||
        dw.max.y - dw.min.y + 1 != spec_.height)
      return false;
    const size_t n = size_t(end - begin);
    std::vector<ExrChannelTarget> targets;
    for (int c = begin; c < end; ++c)
      targets.push_back({spec_.channelnames[size_t(c)], dst + (c - begin), n});
    return read_deflate_scanlines(file, targets);
  } catch (const std::exception&) {
    return false;  // OpenImageIO reads it, or says why it cannot
  }
}

std::vector<float> ImageFile::read(int c) {
  std::vector<float> v(size_t(spec_.width) * spec_.height);
  if (read_deflate(c, c + 1, v.data())) return v;
  if (!in_->read_image(0, 0, c, c + 1, OIIO::TypeDesc::FLOAT, v.data()))
    throw Error(Exit::input,
                path_ + ": cannot read channel " + spec_.channelnames[c] + ": " + in_->geterror());
  return v;
}

std::vector<float> ImageFile::read_range(int begin, int end) {
  std::vector<float> v(size_t(spec_.width) * spec_.height * size_t(end - begin));
  if (read_deflate(begin, end, v.data())) return v;
  if (!in_->read_image(0, 0, begin, end, OIIO::TypeDesc::FLOAT, v.data()))
    throw Error(Exit::input, path_ + ": cannot read channels " + spec_.channelnames[begin] +
                                 " to " + spec_.channelnames[end - 1] + ": " + in_->geterror());
  return v;
}

MemoryChannels::MemoryChannels(std::string name, int width, int height,
                               std::vector<Channel> channels, int x, int y)
    : name_(std::move(name)),
      width_(width),
      height_(height),
      x_(x),
      y_(y),
      channels_(std::move(channels)) {
  for (const Channel& c : channels_) names_.push_back(c.name);
}

std::vector<float> MemoryChannels::read(int c) {
  const Channel& ch = channels_.at(size_t(c));
  std::vector<float> v(size_t(width_) * height_, 1.f);
  if (ch.src)
    for (size_t i = 0; i < v.size(); ++i) v[i] = ch.src[i * ch.stride];
  return v;
}

namespace {

// The part of `src` that lies where `at` has its pixels (at's window within src's).
class WindowOf : public ChannelSource {
 public:
  WindowOf(ChannelSource& src, const ChannelSource& at) : src_(src), at_(at) {}
  const std::string& name() const override { return src_.name(); }
  int width() const override { return at_.width(); }
  int height() const override { return at_.height(); }
  int x() const override { return at_.x(); }
  int y() const override { return at_.y(); }
  const std::vector<std::string>& channel_names() const override { return src_.channel_names(); }
  std::vector<float> read(int c) override {
    const std::vector<float> all = src_.read(c);
    std::vector<float> v(size_t(width()) * size_t(height()));
    const int dx = x() - src_.x(), dy = y() - src_.y();
    for (int j = 0; j < height(); ++j)
      std::copy_n(all.begin() + ptrdiff_t((size_t(j + dy) * size_t(src_.width()) + size_t(dx))),
                  width(), v.begin() + ptrdiff_t(size_t(j) * size_t(width())));
    return v;
  }

 private:
  ChannelSource& src_;
  const ChannelSource& at_;
};

std::string describe_window(const ChannelSource& s) {
  std::string d = std::to_string(s.width()) + "x" + std::to_string(s.height());
  if (s.x() != 0 || s.y() != 0)
    d += " at (" + std::to_string(s.x()) + ", " + std::to_string(s.y()) + ")";
  return d;
}

int rank(const std::string& comp) {
  static const std::vector<std::string> order = {"R", "G", "B", "A", "X", "Y",
                                                 "Z", "W", "r", "g", "b", "a"};
  auto it = std::find(order.begin(), order.end(), comp);
  return it == order.end() ? int(order.size()) : int(it - order.begin());
}

class Parser {
 public:
  Parser(std::string option, std::string text)
      : option_(std::move(option)), text_(std::move(text)) {}

  LayerExpr parse() {
    LayerExpr e = sum();
    skip_space();
    if (pos_ < text_.size()) fail(std::string("unexpected '") + text_[pos_] + "'");
    return e;
  }

 private:
  static bool is_operator(char c) { return c == '+' || c == '*' || c == '(' || c == ')'; }

  void skip_space() {
    while (pos_ < text_.size() && std::isspace(static_cast<unsigned char>(text_[pos_]))) ++pos_;
  }
  bool accept(char c) {
    skip_space();
    if (pos_ < text_.size() && text_[pos_] == c) {
      ++pos_;
      return true;
    }
    return false;
  }
  [[noreturn]] void fail(const std::string& what) const {
    throw Error(Exit::usage, option_ + " '" + text_ + "': " + what + " at character " +
                                 std::to_string(pos_ + 1) +
                                 " (an expression joins layer names with *, + and parentheses)");
  }
  LayerExpr chain(LayerExpr::Op op, char symbol, LayerExpr (Parser::*operand)()) {
    LayerExpr e{op, "", {}};
    e.args.push_back((this->*operand)());
    while (accept(symbol)) e.args.push_back((this->*operand)());
    return e.args.size() == 1 ? std::move(e.args[0]) : std::move(e);
  }
  LayerExpr sum() { return chain(LayerExpr::add, '+', &Parser::product); }
  LayerExpr product() { return chain(LayerExpr::mul, '*', &Parser::operand); }
  LayerExpr operand() {
    if (accept('(')) {
      LayerExpr e = sum();
      if (!accept(')')) fail(pos_ < text_.size() ? "expected ')'" : "missing ')'");
      return e;
    }
    skip_space();
    size_t end = pos_;
    while (end < text_.size() && !is_operator(text_[end])) ++end;
    std::string_view name(text_.data() + pos_, end - pos_);
    while (!name.empty() && std::isspace(static_cast<unsigned char>(name.back())))
      name.remove_suffix(1);
    if (name.empty())
      fail(pos_ < text_.size() ? std::string("expected a layer name before '") + text_[pos_] + "'"
                               : std::string("expected a layer name"));
    pos_ = end;
    return {LayerExpr::layer, std::string(name), {}};
  }

  std::string option_, text_;
  size_t pos_ = 0;
};

}  // namespace

std::vector<int> layer_channels(const ChannelSource& im, const std::string& layer) {
  const auto& names = im.channel_names();
  const int nc = int(names.size());
  for (int c = 0; c < nc; ++c)
    if (names[c] == layer) return {c};
  std::vector<int> out;
  for (int c = 0; c < nc; ++c)
    if (names[c].rfind(layer + ".", 0) == 0 &&
        names[c].find('.', layer.size() + 1) == std::string::npos)
      out.push_back(c);
  if (out.empty()) {
    std::string prefix;
    for (int c = 0; c < nc && prefix.empty(); ++c) {
      const auto pos = names[c].find("." + layer + ".");
      if (pos != std::string::npos &&
          names[c].find('.', pos + layer.size() + 2) == std::string::npos)
        prefix = names[c].substr(0, pos + layer.size() + 1);
    }
    if (!prefix.empty()) return layer_channels(im, prefix);
  }
  std::stable_sort(out.begin(), out.end(), [&](int a, int b) {
    return rank(names[a].substr(names[a].rfind('.') + 1)) <
           rank(names[b].substr(names[b].rfind('.') + 1));
  });
  if (out.empty()) throw Error(Exit::missing_pass, im.name() + ": no layer '" + layer + "'");
  return out;
}

LayerExpr parse_layer_expr(const std::string& option, const std::string& text) {
  return Parser(option, text).parse();
}

std::string to_string(const LayerExpr& e) {
  if (e.op == LayerExpr::layer) return e.name;
  std::string s;
  for (const auto& a : e.args) {
    if (!s.empty()) s += e.op == LayerExpr::add ? "+" : "*";
    s += e.op == LayerExpr::mul && a.op == LayerExpr::add ? "(" + to_string(a) + ")" : to_string(a);
  }
  return s;
}

// The same tree as the expression, leaves holding channel indices.
struct BoundExpr::Node {
  LayerExpr::Op op = LayerExpr::layer;
  std::vector<int> channels;  // op == layer
  std::vector<Node> args;     // op == add, mul
  size_t nchannels = 0;       // of the result
  std::string text;           // the (sub)expression, for messages
};

namespace {

using Node = BoundExpr::Node;

// The channel of leaf `b` that channel k of the result uses (a 1-channel leaf serves all k).
int leaf_channel(const Node& b, size_t k) {
  return b.channels.size() == 1 ? b.channels[0] : b.channels[k];
}

Node resolve(const LayerExpr& e, const ChannelSource& im, const std::string& option,
             const std::string& whole) {
  Node b{e.op, {}, {}, 0, to_string(e)};
  if (e.op == LayerExpr::layer) {
    try {
      b.channels = layer_channels(im, e.name);
    } catch (const Error& err) {
      if (whole == e.name) throw;  // a plain layer: the message of old
      throw Error(err.code(), std::string(err.what()) + " (in " + option + " '" + whole + "')");
    }
    b.nchannels = b.channels.size();
    return b;
  }
  for (const auto& a : e.args) {
    b.args.push_back(resolve(a, im, option, whole));
    b.nchannels = std::max(b.nchannels, b.args.back().nchannels);
  }
  for (const auto& a : b.args)
    if (a.nchannels != b.nchannels && a.nchannels != 1) {
      const Node& wide = *std::find_if(b.args.begin(), b.args.end(),
                                       [&](const Node& x) { return x.nchannels == b.nchannels; });
      throw Error(Exit::usage, option + " '" + whole + "': in " + im.name() + " '" + wide.text +
                                   "' has " + std::to_string(wide.nchannels) + " channels but '" +
                                   a.text + "' has " + std::to_string(a.nchannels) +
                                   " (operands need the same number of channels, or 1)");
    }
  return b;
}

void for_each_leaf(const Node& b, size_t k, const std::function<void(int)>& f) {
  if (b.op == LayerExpr::layer) return f(leaf_channel(b, k));
  for (const auto& a : b.args) for_each_leaf(a, k, f);
}

}  // namespace

BoundExpr::BoundExpr(const LayerExpr& e, ChannelSource& im, const std::string& option,
                     const std::string& text)
    : root_(std::make_unique<Node>(resolve(e, im, option, text))), im_(&im) {}
BoundExpr::~BoundExpr() = default;
BoundExpr::BoundExpr(BoundExpr&&) noexcept = default;

size_t BoundExpr::channels() const {
  return root_->nchannels;
}

std::string BoundExpr::channel_name(size_t k) const {
  const Node& b = *root_;
  const auto& names = im_->channel_names();
  if (b.op == LayerExpr::layer) return names[leaf_channel(b, k)];
  const Node* leaf = nullptr;
  std::function<void(const Node&)> find = [&](const Node& x) {
    if (leaf) return;
    if (x.op == LayerExpr::layer) {
      if (x.nchannels == b.nchannels) leaf = &x;
      return;
    }
    for (const auto& a : x.args) find(a);
  };
  find(b);
  const std::string& c = names[leaf_channel(*leaf, k)];
  const auto dot = c.rfind('.');
  return "(" + b.text + ")" + (dot == std::string::npos ? "" : c.substr(dot));
}

void BoundExpr::prepare(size_t n) {
  uses_.clear();
  cache_.clear();
  for (size_t k = 0; k < n; ++k) for_each_leaf(*root_, k, [&](int c) { ++uses_[c]; });
}

std::vector<float> BoundExpr::get(int c) {
  auto it = cache_.find(c);
  if (it == cache_.end()) it = cache_.emplace(c, im_->read(c)).first;
  if (--uses_[c] > 0) return it->second;
  std::vector<float> v = std::move(it->second);
  cache_.erase(it);
  return v;
}

std::vector<float> BoundExpr::evaluate(const Node& b, size_t k) {
  if (b.op == LayerExpr::layer) return get(leaf_channel(b, k));
  std::vector<float> acc = evaluate(b.args[0], k);
  for (size_t i = 1; i < b.args.size(); ++i) {
    const std::vector<float> v = evaluate(b.args[i], k);
    if (b.op == LayerExpr::add)
      for (size_t p = 0; p < acc.size(); ++p) acc[p] += v[p];
    else
      for (size_t p = 0; p < acc.size(); ++p) acc[p] *= v[p];
  }
  return acc;
}

std::vector<float> BoundExpr::channel(size_t k) {
  return evaluate(*root_, k);
}

std::vector<unsigned char> make_mask(ChannelSource& test, ChannelSource& ref, const MaskSpec& o,
                                     std::string& described) {
  const size_t n = size_t(ref.width()) * ref.height();
  std::vector<unsigned char> m(n, 1);
  if (o.mask == "none") {
    described = "none";
    return m;
  }
  auto find = [](const ChannelSource& im, auto pred) {
    const auto& names = im.channel_names();
    for (size_t c = 0; c < names.size(); ++c)
      if (pred(names[c])) return int(c);
    return -1;
  };
  auto ends_with = [](const std::string& s, const std::string& t) {
    return s.size() >= t.size() && s.compare(s.size() - t.size(), t.size(), t) == 0;
  };
  if (o.mask != "auto") {
    ChannelSource* im = &ref;
    int c = find(ref, [&](const std::string& s) { return s == o.mask; });
    if (c < 0) {
      im = &test;
      c = find(test, [&](const std::string& s) { return s == o.mask; });
    }
    if (c < 0)
      throw Error(Exit::missing_pass,
                  "--mask: no channel '" + o.mask + "' in " + ref.name() + " or " + test.name());
    const auto v = im->read(c);
    for (size_t i = 0; i < n; ++i) m[i] = v[i] != 0.f;
    described = o.mask + " != 0";
    return m;
  }
  // The front depth: not a back-face layer's (samples/blender/backfaces.py), which sorts first.
  int c = find(ref, [&](const std::string& s) {
    return (ends_with(s, ".Depth.Z") && s != "BackFaces.Depth.Z") || s == "Z" || s == "depth.Z";
  });
  if (c >= 0) {
    const auto v = ref.read(c);
    for (size_t i = 0; i < n; ++i) m[i] = v[i] < o.background_depth;
    described = ref.channel_names()[c] + " < background";
    return m;
  }
  c = find(ref, [&](const std::string& s) { return ends_with(s, ".A") || s == "A"; });
  if (c >= 0) {
    const auto v = ref.read(c);
    for (size_t i = 0; i < n; ++i) m[i] = v[i] > 0.f;
    described = ref.channel_names()[c] + " > 0";
    return m;
  }
  described = "none (no depth or alpha in the reference)";
  return m;
}

LayerComparison compare_layers(ChannelSource& test, const LayerExpr& test_expr,
                               const std::string& test_option, const std::string& test_text,
                               ChannelSource& ref, const LayerExpr& ref_expr,
                               const std::string& ref_option, const std::string& ref_text,
                               const MaskSpec& mask, bool colour_only,
                               const std::vector<unsigned char>* region, bool keep_planes) {
  const bool same = test.width() == ref.width() && test.height() == ref.height() &&
                    test.x() == ref.x() && test.y() == ref.y();
  const bool inside = ref.x() >= test.x() && ref.y() >= test.y() &&
                      int64_t(ref.x()) + ref.width() <= int64_t(test.x()) + test.width() &&
                      int64_t(ref.y()) + ref.height() <= int64_t(test.y()) + test.height();
  // Same-sized images whose origins differ are compared pixel for pixel, as before windows
  // were read (a render and a crop written from (0, 0)).
  const bool sized = test.width() == ref.width() && test.height() == ref.height();
  if (!same && !sized && !inside)
    throw Error(Exit::bad_data, test.name() + " is " + describe_window(test) + " but " +
                                    ref.name() + " is " + describe_window(ref) +
                                    ", which does not lie within it");
  WindowOf window(test, ref);
  ChannelSource& t = same || sized ? test : window;
  BoundExpr tb(test_expr, t, test_option, test_text), rb(ref_expr, ref, ref_option, ref_text);
  const size_t n = std::max(tb.channels(), rb.channels());
  if ((tb.channels() != n && tb.channels() != 1) || (rb.channels() != n && rb.channels() != 1))
    throw Error(Exit::usage, "layer '" + to_string(test_expr) + "' has " +
                                 std::to_string(tb.channels()) + " channels but '" +
                                 to_string(ref_expr) + "' has " + std::to_string(rb.channels()));
  LayerComparison out;
  auto valid = make_mask(t, ref, mask, out.mask);
  if (region)
    for (size_t i = 0; i < valid.size() && i < region->size(); ++i)
      valid[i] = valid[i] && (*region)[i];
  tb.prepare(n);
  rb.prepare(n);
  auto is_alpha = [](const std::string& c) {
    return c == "A" || (c.size() > 2 && c.compare(c.size() - 2, 2, ".A") == 0);
  };
  for (size_t k = 0; k < n; ++k) {
    ChannelError ce{tb.channel_name(k), rb.channel_name(k), {}};
    // Evaluated even when left out: the reader hands each channel over once per use.
    auto a = tb.channel(k), b = rb.channel(k);
    if (colour_only && (is_alpha(ce.test) || is_alpha(ce.reference))) continue;
    for (size_t i = 0; i < a.size(); ++i)
      if (valid[i]) ce.stats.add(a[i], b[i]);
    out.overall.add(ce.stats);
    out.channels.push_back(std::move(ce));
    if (keep_planes) {
      out.test_planes.push_back(std::move(a));
      out.ref_planes.push_back(std::move(b));
    }
  }
  if (keep_planes) out.valid = std::move(valid);
  return out;
}

}  // namespace hbil::io
