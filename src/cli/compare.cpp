// compare.cpp: `hbil compare TEST REFERENCE --layer L`: the accuracy numbers of this project.
//
// --layer and --ref-layer are layer expressions: layers combined per channel with * and +
// and parentheses. Cycles writes no indirect-diffuse layer; the reference for hbil's
// `indirect` is DiffCol*DiffInd, for a composite DiffCol*(DiffDir+DiffInd)+Emit.
#include <OpenImageIO/imageio.h>

#include <algorithm>
#include <cctype>
#include <cstdio>
#include <functional>
#include <iostream>
#include <map>
#include <nlohmann/json.hpp>
#include <string_view>

#include "cli/commands.h"
#include "hbil/error.h"
#include "hbil/error_stats.h"
#include "io/sequence.h"

namespace hbil::cli {

namespace {

struct Options {
  std::string test, reference, layer, ref_layer, mask = "auto", frames;
  bool json = false;
  double background_depth = Params{}.background_depth;
};

struct Image {
  std::string path;
  OIIO::ImageSpec spec;
  std::unique_ptr<OIIO::ImageInput> in;
};

Image open(const std::string& path) {
  Image im{path, {}, OIIO::ImageInput::open(path)};
  if (!im.in) throw Error(Exit::input, path + ": cannot read: " + OIIO::geterror());
  im.spec = im.in->spec();
  return im;
}

int rank(const std::string& comp) {
  static const std::vector<std::string> order = {"R", "G", "B", "A", "X", "Y",
                                                 "Z", "W", "r", "g", "b", "a"};
  auto it = std::find(order.begin(), order.end(), comp);
  return it == order.end() ? int(order.size()) : int(it - order.begin());
}

// Channels of layer L: the channel named L, else <L>.<comp>, else <anything>.<L>.<comp>
// (Blender's view-layer prefix), ordered R G B A X Y Z W.
std::vector<int> layer_channels(const Image& im, const std::string& layer) {
  const auto& names = im.spec.channelnames;
  for (int c = 0; c < im.spec.nchannels; ++c)
    if (names[c] == layer) return {c};
  std::vector<int> out;
  for (int c = 0; c < im.spec.nchannels; ++c)
    if (names[c].rfind(layer + ".", 0) == 0 &&
        names[c].find('.', layer.size() + 1) == std::string::npos)
      out.push_back(c);
  if (out.empty()) {
    std::string prefix;
    for (int c = 0; c < im.spec.nchannels && prefix.empty(); ++c) {
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
  if (out.empty()) throw Error(Exit::missing_pass, im.path + ": no layer '" + layer + "'");
  return out;
}

std::vector<float> read_channel(Image& im, int c) {
  std::vector<float> v(size_t(im.spec.width) * im.spec.height);
  if (!im.in->read_image(0, 0, c, c + 1, OIIO::TypeDesc::FLOAT, v.data()))
    throw Error(Exit::input, im.path + ": cannot read channel " + im.spec.channelnames[c] + ": " +
                                 im.in->geterror());
  return v;
}

// ---------------------------------------------------------------------------------------
// Layer expressions
//
//   sum     := product ('+' product)*
//   product := operand ('*' operand)*
//   operand := NAME | '(' sum ')'
//
// A NAME is any text without + * ( ), spaces around it dropped, resolved by
// layer_channels. A plain layer name is an expression of one operand. Operands have the
// same number of channels, or 1 (used for every channel); channel k of the result is the
// arithmetic of channel k of each operand.

struct Expr {
  enum Op { layer, add, mul } op = layer;
  std::string name;        // op == layer
  std::vector<Expr> args;  // op == add, mul: two or more
};

class ExprParser {
 public:
  // `option` (--layer, --ref-layer) only names the expression in messages.
  ExprParser(std::string option, std::string text)
      : option_(std::move(option)), text_(std::move(text)) {}

  // Throws Error(Exit::usage) naming the expression and the character where it fails.
  Expr parse() {
    Expr e = sum();
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
  Expr chain(Expr::Op op, char symbol, Expr (ExprParser::*operand)()) {
    Expr e{op, "", {}};
    e.args.push_back((this->*operand)());
    while (accept(symbol)) e.args.push_back((this->*operand)());
    return e.args.size() == 1 ? std::move(e.args[0]) : std::move(e);
  }
  Expr sum() { return chain(Expr::add, '+', &ExprParser::product); }
  Expr product() { return chain(Expr::mul, '*', &ExprParser::operand); }
  Expr operand() {
    if (accept('(')) {
      Expr e = sum();
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
    return {Expr::layer, std::string(name), {}};
  }

  std::string option_, text_;
  size_t pos_ = 0;
};

// The expression in its shortest form: no spaces, parentheses only around a sum in a product.
std::string to_string(const Expr& e) {
  if (e.op == Expr::layer) return e.name;
  std::string s;
  for (const auto& a : e.args) {
    if (!s.empty()) s += e.op == Expr::add ? "+" : "*";
    s += e.op == Expr::mul && a.op == Expr::add ? "(" + to_string(a) + ")" : to_string(a);
  }
  return s;
}

// An expression with each layer looked up in one image: the same tree, leaves holding
// channel indices.
struct Bound {
  Expr::Op op = Expr::layer;
  std::vector<int> channels;  // op == layer
  std::vector<Bound> args;    // op == add, mul
  size_t nchannels = 0;       // of the result
  std::string text;           // the (sub)expression, for messages
};

// The channel of leaf `b` that channel k of the result uses (a 1-channel leaf serves all k).
int leaf_channel(const Bound& b, size_t k) {
  return b.channels.size() == 1 ? b.channels[0] : b.channels[k];
}

Bound resolve(const Expr& e, const Image& im, const std::string& option, const std::string& whole) {
  Bound b{e.op, {}, {}, 0, to_string(e)};
  if (e.op == Expr::layer) {
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
      const Bound& wide = *std::find_if(b.args.begin(), b.args.end(),
                                        [&](const Bound& x) { return x.nchannels == b.nchannels; });
      throw Error(Exit::usage, option + " '" + whole + "': in " + im.path + " '" + wide.text +
                                   "' has " + std::to_string(wide.nchannels) + " channels but '" +
                                   a.text + "' has " + std::to_string(a.nchannels) +
                                   " (operands need the same number of channels, or 1)");
    }
  return b;
}

void for_each_leaf(const Bound& b, size_t k, const std::function<void(int)>& f) {
  if (b.op == Expr::layer) return f(leaf_channel(b, k));
  for (const auto& a : b.args) for_each_leaf(a, k, f);
}

// The name of channel k of the result: the channel itself for a plain layer, else the
// expression in parentheses with the component of its first widest layer, "(DiffCol*DiffInd).R".
std::string channel_name(const Bound& b, const Image& im, size_t k) {
  if (b.op == Expr::layer) return im.spec.channelnames[leaf_channel(b, k)];
  const Bound* leaf = nullptr;
  std::function<void(const Bound&)> find = [&](const Bound& x) {
    if (leaf) return;
    if (x.op == Expr::layer) {
      if (x.nchannels == b.nchannels) leaf = &x;
      return;
    }
    for (const auto& a : x.args) find(a);
  };
  find(b);
  const std::string& c = im.spec.channelnames[leaf_channel(*leaf, k)];
  const auto dot = c.rfind('.');
  return "(" + b.text + ")" + (dot == std::string::npos ? "" : c.substr(dot));
}

// Channels of one image read for an evaluation, each read once and kept only while a
// later use is still to come.
class ChannelReader {
 public:
  // `uses`: how many times each channel will be asked for.
  ChannelReader(Image& im, std::map<int, int> uses) : im_(im), uses_(std::move(uses)) {}
  std::vector<float> get(int c) {
    auto it = cache_.find(c);
    if (it == cache_.end()) it = cache_.emplace(c, read_channel(im_, c)).first;
    if (--uses_[c] > 0) return it->second;
    std::vector<float> v = std::move(it->second);
    cache_.erase(it);
    return v;
  }

 private:
  Image& im_;
  std::map<int, int> uses_;
  std::map<int, std::vector<float>> cache_;
};

// Channel k of the result, per pixel.
std::vector<float> evaluate(const Bound& b, size_t k, ChannelReader& reader) {
  if (b.op == Expr::layer) return reader.get(leaf_channel(b, k));
  std::vector<float> acc = evaluate(b.args[0], k, reader);
  for (size_t i = 1; i < b.args.size(); ++i) {
    const std::vector<float> v = evaluate(b.args[i], k, reader);
    if (b.op == Expr::add)
      for (size_t p = 0; p < acc.size(); ++p) acc[p] += v[p];
    else
      for (size_t p = 0; p < acc.size(); ++p) acc[p] *= v[p];
  }
  return acc;
}

// Channels 0..n-1 of an expression over one image, one at a time.
class Evaluator {
 public:
  Evaluator(Image& im, const Bound& b, size_t n) : b_(b), reader_(im, count_uses(b, n)) {}
  std::vector<float> channel(size_t k) { return evaluate(b_, k, reader_); }

 private:
  static std::map<int, int> count_uses(const Bound& b, size_t n) {
    std::map<int, int> uses;
    for (size_t k = 0; k < n; ++k) for_each_leaf(b, k, [&](int c) { ++uses[c]; });
    return uses;
  }
  const Bound& b_;
  ChannelReader reader_;
};

// ---------------------------------------------------------------------------------------

// Valid pixels: --mask none: all; CHANNEL: where that channel (reference, else test) is
// non-zero; auto: the reference's depth below background_depth, else its alpha above 0.
std::vector<unsigned char> make_mask(Image& test, Image& ref, const Options& o,
                                     std::string& described) {
  const size_t n = size_t(ref.spec.width) * ref.spec.height;
  std::vector<unsigned char> m(n, 1);
  if (o.mask == "none") {
    described = "none";
    return m;
  }
  auto find = [](const Image& im, auto pred) {
    for (int c = 0; c < im.spec.nchannels; ++c)
      if (pred(im.spec.channelnames[c])) return c;
    return -1;
  };
  auto ends_with = [](const std::string& s, const std::string& t) {
    return s.size() >= t.size() && s.compare(s.size() - t.size(), t.size(), t) == 0;
  };
  if (o.mask != "auto") {
    Image* im = &ref;
    int c = find(ref, [&](const std::string& s) { return s == o.mask; });
    if (c < 0) {
      im = &test;
      c = find(test, [&](const std::string& s) { return s == o.mask; });
    }
    if (c < 0)
      throw Error(Exit::missing_pass,
                  "--mask: no channel '" + o.mask + "' in " + ref.path + " or " + test.path);
    const auto v = read_channel(*im, c);
    for (size_t i = 0; i < n; ++i) m[i] = v[i] != 0.f;
    described = o.mask + " != 0";
    return m;
  }
  // The front depth: not a back-face layer's (samples/blender/backfaces.py), which sorts first.
  int c = find(ref, [&](const std::string& s) {
    return (ends_with(s, ".Depth.Z") && s != "BackFaces.Depth.Z") || s == "Z" || s == "depth.Z";
  });
  if (c >= 0) {
    const auto v = read_channel(ref, c);
    for (size_t i = 0; i < n; ++i) m[i] = v[i] < o.background_depth;
    described = ref.spec.channelnames[c] + " < background";
    return m;
  }
  c = find(ref, [&](const std::string& s) { return ends_with(s, ".A") || s == "A"; });
  if (c >= 0) {
    const auto v = read_channel(ref, c);
    for (size_t i = 0; i < n; ++i) m[i] = v[i] > 0.f;
    described = ref.spec.channelnames[c] + " > 0";
    return m;
  }
  described = "none (no depth or alpha in the reference)";
  return m;
}

std::string num(double v) {
  char b[32];
  if (std::isinf(v)) return "inf";
  std::snprintf(b, sizeof b, "%.5f", v);
  return b;
}

nlohmann::json stats_json(const ErrorStats& s) {
  return {{"pixels", s.count},
          {"rmse", s.rmse()},
          {"mean_error", s.mean_error()},
          {"psnr", std::isinf(s.psnr()) ? nlohmann::json("inf") : nlohmann::json(s.psnr())}};
}

void compare(const Options& o) {
  const io::FramePattern tp(o.test), rp(o.reference);
  std::vector<int> frames;
  if (tp.is_sequence()) {
    if (!o.frames.empty()) {
      const auto r = io::parse_frame_range(o.frames);
      for (int f = r.first; f <= r.last; ++f) frames.push_back(f);
    } else {
      frames = tp.existing_frames();
    }
    if (frames.empty()) throw Error(Exit::input, o.test + ": no frames found matching the pattern");
  } else {
    frames = {0};
  }
  // Both expressions are parsed before any file is opened: a malformed one is a usage error.
  const Expr test_expr = ExprParser("--layer", o.layer).parse();
  const bool ref_default = o.ref_layer.empty();
  const std::string ref_option = ref_default ? "--layer" : "--ref-layer",
                    ref_text = ref_default ? o.layer : o.ref_layer;
  const Expr ref_expr = ExprParser(ref_option, ref_text).parse();
  const std::string layer = to_string(test_expr), ref_layer = to_string(ref_expr);
  std::vector<std::pair<std::string, std::string>> pairs;  // channel names compared
  std::vector<ErrorStats> per_channel;
  ErrorStats all;
  nlohmann::json jframes = nlohmann::json::array();
  std::string mask_desc;
  for (int f : frames) {
    Image test = open(tp.path(f)), ref = open(rp.path(f));
    if (test.spec.width != ref.spec.width || test.spec.height != ref.spec.height)
      throw Error(Exit::bad_data, tp.path(f) + " is " + std::to_string(test.spec.width) + "x" +
                                      std::to_string(test.spec.height) + " but " + rp.path(f) +
                                      " is " + std::to_string(ref.spec.width) + "x" +
                                      std::to_string(ref.spec.height));
    const Bound tb = resolve(test_expr, test, "--layer", o.layer),
                rb = resolve(ref_expr, ref, ref_option, ref_text);
    // One channel against several is compared with each (ao.Y against AO.R, AO.G, AO.B).
    const size_t n = std::max(tb.nchannels, rb.nchannels);
    if ((tb.nchannels != n && tb.nchannels != 1) || (rb.nchannels != n && rb.nchannels != 1))
      throw Error(Exit::usage, "layer '" + layer + "' has " + std::to_string(tb.nchannels) +
                                   " channels but '" + ref_layer + "' has " +
                                   std::to_string(rb.nchannels));
    if (per_channel.empty()) {
      per_channel.resize(n);
      for (size_t k = 0; k < n; ++k)
        pairs.emplace_back(channel_name(tb, test, k), channel_name(rb, ref, k));
    }
    const auto mask = make_mask(test, ref, o, mask_desc);
    Evaluator te(test, tb, n), re(ref, rb, n);
    ErrorStats frame_stats;
    for (size_t k = 0; k < n; ++k) {
      const auto a = te.channel(k), b = re.channel(k);
      ErrorStats s;
      for (size_t i = 0; i < a.size(); ++i)
        if (mask[i]) s.add(a[i], b[i]);
      per_channel[k].add(s);
      frame_stats.add(s);
    }
    all.add(frame_stats);
    nlohmann::json jf = stats_json(frame_stats);
    jf["frame"] = f;
    jf["test"] = tp.path(f);
    jf["reference"] = rp.path(f);
    jframes.push_back(jf);
  }
  if (o.json) {
    nlohmann::json j;
    j["test"] = o.test;
    j["reference"] = o.reference;
    j["layer"] = layer;
    j["ref_layer"] = ref_layer;
    j["mask"] = mask_desc;
    j["frames"] = jframes;
    j["channels"] = nlohmann::json::array();
    for (size_t k = 0; k < pairs.size(); ++k) {
      nlohmann::json c = stats_json(per_channel[k]);
      c["test"] = pairs[k].first;
      c["reference"] = pairs[k].second;
      j["channels"].push_back(c);
    }
    j["overall"] = stats_json(all);
    std::cout << j.dump(2) << "\n";
    return;
  }
  std::cout << "mask: " << mask_desc << "\n";
  // The first column is as wide as its longest label (expressions make long ones).
  std::vector<std::string> labels;
  for (const auto& [t, r] : pairs) labels.push_back(t + " vs " + r);
  int w = 28;
  for (const auto& l : labels) w = std::max(w, int(l.size()));
  std::printf("%-*s %10s %10s %10s %10s\n", w, "", "pixels", "rmse", "mean", "psnr");
  if (frames.size() > 1)
    for (const auto& jf : jframes)
      std::printf("%-*s %10zu %10s %10s %10s\n", w,
                  ("frame " + std::to_string(jf["frame"].get<int>())).c_str(),
                  jf["pixels"].get<size_t>(), num(jf["rmse"]).c_str(),
                  num(jf["mean_error"]).c_str(),
                  jf["psnr"].is_string() ? "inf" : num(jf["psnr"]).c_str());
  for (size_t k = 0; k < pairs.size(); ++k)
    std::printf("%-*s %10zu %10s %10s %10s\n", w, labels[k].c_str(), per_channel[k].count,
                num(per_channel[k].rmse()).c_str(), num(per_channel[k].mean_error()).c_str(),
                num(per_channel[k].psnr()).c_str());
  std::printf("%-*s %10zu %10s %10s %10s\n", w, "overall", all.count, num(all.rmse()).c_str(),
              num(all.mean_error()).c_str(), num(all.psnr()).c_str());
}

}  // namespace

void add_compare(CLI::App& app) {
  auto o = std::make_shared<Options>();
  CLI::App* cmd = app.add_subcommand(
      "compare",
      "RMSE, mean error and PSNR (peak 1) of a layer against a reference, over valid pixels");
  cmd->add_option("TEST", o->test, "EXR frame or frame pattern to judge")->required();
  cmd->add_option("REFERENCE", o->reference, "reference EXR frame or frame pattern")->required();
  cmd->add_option("--layer", o->layer,
                  "layer (or channel) of TEST, or an expression of layers with * + ( ), e.g. ao")
      ->required();
  cmd->add_option("--ref-layer", o->ref_layer,
                  "layer or layer expression of REFERENCE (default: --layer), e.g. AO, "
                  "'DiffCol*DiffInd', 'DiffCol*(DiffDir+DiffInd)+Emit'");
  cmd->add_option("--mask", o->mask,
                  "valid pixels: auto (reference depth, else alpha), none, or a channel name")
      ->capture_default_str();
  cmd->add_option("--frames", o->frames,
                  "frame range A-B of the patterns (default: every TEST frame found)");
  cmd->add_option("--background-depth", o->background_depth,
                  "depth at or beyond which --mask auto drops a pixel")
      ->capture_default_str();
  cmd->add_flag("--json", o->json, "print JSON instead of a table");
  cmd->callback([o] { compare(*o); });
}

}  // namespace hbil::cli
