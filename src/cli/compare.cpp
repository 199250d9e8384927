// compare.cpp: `hbil compare TEST REFERENCE --layer L`: the accuracy numbers of this project.
#include <OpenImageIO/imageio.h>

#include <algorithm>
#include <cstdio>
#include <iostream>
#include <map>
#include <nlohmann/json.hpp>

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
  int c = find(ref, [&](const std::string& s) {
    return ends_with(s, ".Depth.Z") || s == "Z" || s == "depth.Z";
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
  const std::string ref_layer = o.ref_layer.empty() ? o.layer : o.ref_layer;
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
    std::vector<int> tc = layer_channels(test, o.layer), rc = layer_channels(ref, ref_layer);
    // One channel against several is compared with each (ao.Y against AO.R, AO.G, AO.B).
    if (tc.size() != rc.size()) {
      if (tc.size() == 1)
        tc.assign(rc.size(), tc[0]);
      else if (rc.size() == 1)
        rc.assign(tc.size(), rc[0]);
      else
        throw Error(Exit::usage, "layer '" + o.layer + "' has " + std::to_string(tc.size()) +
                                     " channels but '" + ref_layer + "' has " +
                                     std::to_string(rc.size()));
    }
    if (per_channel.empty()) {
      per_channel.resize(tc.size());
      for (size_t k = 0; k < tc.size(); ++k)
        pairs.emplace_back(test.spec.channelnames[tc[k]], ref.spec.channelnames[rc[k]]);
    }
    const auto mask = make_mask(test, ref, o, mask_desc);
    ErrorStats frame_stats;
    for (size_t k = 0; k < tc.size(); ++k) {
      const auto a = read_channel(test, tc[k]), b = read_channel(ref, rc[k]);
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
    j["layer"] = o.layer;
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
  std::printf("%-28s %10s %10s %10s %10s\n", "", "pixels", "rmse", "mean", "psnr");
  if (frames.size() > 1)
    for (const auto& jf : jframes)
      std::printf("%-28s %10zu %10s %10s %10s\n",
                  ("frame " + std::to_string(jf["frame"].get<int>())).c_str(),
                  jf["pixels"].get<size_t>(), num(jf["rmse"]).c_str(),
                  num(jf["mean_error"]).c_str(),
                  jf["psnr"].is_string() ? "inf" : num(jf["psnr"]).c_str());
  for (size_t k = 0; k < pairs.size(); ++k)
    std::printf("%-28s %10zu %10s %10s %10s\n", (pairs[k].first + " vs " + pairs[k].second).c_str(),
                per_channel[k].count, num(per_channel[k].rmse()).c_str(),
                num(per_channel[k].mean_error()).c_str(), num(per_channel[k].psnr()).c_str());
  std::printf("%-28s %10zu %10s %10s %10s\n", "overall", all.count, num(all.rmse()).c_str(),
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
  cmd->add_option("--layer", o->layer, "layer (or channel) of TEST, e.g. ao")->required();
  cmd->add_option("--ref-layer", o->ref_layer, "layer of REFERENCE (default: --layer), e.g. AO");
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
