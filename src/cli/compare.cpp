// compare.cpp: `hbil compare TEST REFERENCE --layer L`: the accuracy numbers of this project.
//
// --layer and --ref-layer are layer expressions (io/layer_expr.h): layers combined per
// channel with * and + and parentheses.
#include <algorithm>
#include <cstdio>
#include <iostream>
#include <nlohmann/json.hpp>

#include "cli/commands.h"
#include "hbil/error.h"
#include "hbil/error_stats.h"
#include "io/layer_expr.h"
#include "io/sequence.h"

namespace hbil::cli {

namespace {

struct Options {
  std::string test, reference, layer, ref_layer, mask = "auto", frames;
  bool json = false;
  double background_depth = Params{}.background_depth;
};

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
      frames = io::parse_frame_list(o.frames);
    } else {
      frames = tp.existing_frames();
    }
    if (frames.empty()) throw Error(Exit::input, o.test + ": no frames found matching the pattern");
  } else {
    frames = {0};
  }
  // Both expressions are parsed before any file is opened: a malformed one is a usage error.
  const io::LayerExpr test_expr = io::parse_layer_expr("--layer", o.layer);
  const bool ref_default = o.ref_layer.empty();
  const std::string ref_option = ref_default ? "--layer" : "--ref-layer",
                    ref_text = ref_default ? o.layer : o.ref_layer;
  const io::LayerExpr ref_expr = io::parse_layer_expr(ref_option, ref_text);
  const std::string layer = io::to_string(test_expr), ref_layer = io::to_string(ref_expr);
  std::vector<std::pair<std::string, std::string>> pairs;  // channel names compared
  std::vector<ErrorStats> per_channel;
  ErrorStats all;
  nlohmann::json jframes = nlohmann::json::array();
  std::string mask_desc;
  for (int f : frames) {
    io::ImageFile test(tp.path(f)), ref(rp.path(f));
    const io::LayerComparison c =
        io::compare_layers(test, test_expr, "--layer", o.layer, ref, ref_expr, ref_option, ref_text,
                           {o.mask, o.background_depth});
    if (per_channel.empty()) {
      per_channel.resize(c.channels.size());
      for (const auto& ch : c.channels) pairs.emplace_back(ch.test, ch.reference);
    }
    for (size_t k = 0; k < c.channels.size() && k < per_channel.size(); ++k)
      per_channel[k].add(c.channels[k].stats);
    mask_desc = c.mask;
    all.add(c.overall);
    nlohmann::json jf = stats_json(c.overall);
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
  cmd->add_option(
      "--frames", o->frames,
      "frames of the patterns: N, A-B, A-BxSTEP, 1,3,5-8 (default: every TEST frame found)");
  cmd->add_option("--background-depth", o->background_depth,
                  "depth at or beyond which --mask auto drops a pixel")
      ->capture_default_str();
  cmd->add_flag("--json", o->json, "print JSON instead of a table");
  cmd->callback([o] { compare(*o); });
}

}  // namespace hbil::cli
