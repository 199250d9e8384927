// params_test.cpp: the parameter table, its JSON round trip, validation errors, --set
// assignments and the shipped presets.

#include "hbil/params.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <set>
#include <string>
#include <vector>

#include "hbil/error.h"
#include "io/preset_file.h"
#include "test_util.h"

namespace hbil {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using test::expect_error;

// A parameter set that differs from the defaults in every kind of key.
Params non_default() {
  Params p;
  p.radius = 0.37;
  p.slices = 3;
  p.slices_auto = false;
  p.steps = 7;
  p.step_power = 1.5;
  p.interleave = false;
  p.spatial_filter = false;
  p.depth_tolerance = 0.125;
  p.background_depth = 5e9;
  p.view_layer = "RenderLayer";
  p.passes["normal"] = json::array({"N.x", "N.y", "N.z"});
  p.passes["depth"] = "Z";
  p.outputs = {"bentcone"};
  return p;
}

TEST(Params, DefaultsAreValidAndWithinTheirRanges) {
  EXPECT_NO_THROW(validate(Params{}, "defaults"));
  const json d = to_json(Params{});
  for (const ParamInfo& info : params_table()) {
    ASSERT_TRUE(d.contains(info.key)) << info.key;
    if (d[info.key].is_string()) {
      EXPECT_EQ(d[info.key], "auto") << info.key;  // derived from the shot
    } else if (!d[info.key].is_boolean()) {
      EXPECT_GE(d[info.key].get<double>(), info.min) << info.key;
      EXPECT_LE(d[info.key].get<double>(), info.max) << info.key;
    }
  }
  EXPECT_EQ(d["radius"], 1.0);
  EXPECT_EQ(d["gather_radius"], "auto");
  EXPECT_EQ(d["thickness"], "auto");
  EXPECT_EQ(d["gather_thickness"], "auto");
  EXPECT_EQ(d["outputs"], json::array({"auto"}));
  EXPECT_EQ(d["passes"]["depth"], "Depth");
  EXPECT_EQ(d["passes"]["normal"], "Normal");
  EXPECT_EQ(d["view_layer"], "");
}

TEST(Params, JsonRoundTripIsIdentity) {
  for (const Params& p : {Params{}, non_default()}) {
    const json j = to_json(p);
    EXPECT_EQ(to_json(params_from_json(j, "round trip")), j);
    // Through text too, as a preset file or hbil:preset is stored.
    EXPECT_EQ(to_json(params_from_json(json::parse(j.dump()), "text")), j);
  }
  const Params back = params_from_json(to_json(non_default()), "round trip");
  EXPECT_EQ(back.radius, 0.37);
  EXPECT_FALSE(back.slices_auto);
  EXPECT_EQ(back.slices, 3);
  EXPECT_FALSE(back.interleave);
  EXPECT_EQ(back.view_layer, "RenderLayer");
  EXPECT_EQ(back.passes.at("normal"), json::array({"N.x", "N.y", "N.z"}));
  EXPECT_EQ(back.outputs, std::vector<std::string>{"bentcone"});
  EXPECT_EQ(back.slice_directions(), 3);
}

TEST(Params, PartialJsonKeepsTheBase) {
  Params base;
  base.slices = 5;
  const Params p = params_from_json(json{{"radius", 2.5}}, "partial", base);
  EXPECT_EQ(p.radius, 2.5);
  EXPECT_EQ(p.slices, 5);
  EXPECT_EQ(p.steps, Params{}.steps);
  // An integer is accepted for a double key.
  EXPECT_EQ(params_from_json(json{{"radius", 3}}, "int").radius, 3.0);
}

TEST(Params, UnknownKeyNamesTheKeyAndTheSource) {
  expect_error(
      [] {
        params_from_json(json{{"radiuss", 1.0}}, "shot/fast.json");
      },
      Exit::preset, {"shot/fast.json", "unknown key 'radiuss'", "radius", "passes"});
  expect_error(
      [] {
        params_from_json(json{{"passes", {{"velocity", "Vector"}}}}, "p.json");
      },
      Exit::preset, {"p.json", "passes.velocity", "depth, normal, position, alpha"});
  expect_error(
      [] {
        params_from_json(json::array({1, 2}), "p.json");
      },
      Exit::preset, {"p.json", "JSON object"});
}

TEST(Params, OutOfRangeNamesKeyValueAndRange) {
  expect_error(
      [] {
        params_from_json(json{{"slices", 0}}, "a.json");
      },
      Exit::preset, {"a.json", "'slices'", "= 0", "[1, 64]"});
  expect_error(
      [] {
        params_from_json(json{{"steps", 300}}, "a.json");
      },
      Exit::preset, {"'steps'", "300", "[1, 256]"});
  expect_error(
      [] {
        params_from_json(json{{"radius", -1.5}}, "a.json");
      },
      Exit::preset, {"'radius'", "-1.5", "1e-06", "1e+06", "world units"});
  expect_error(
      [] {
        params_from_json(json{{"depth_tolerance", 1.5}}, "a.json");
      },
      Exit::preset, {"'depth_tolerance'", "1.5", "[0, 1]"});
  expect_error(
      [] {
        params_from_json(json{{"history_window", 1}}, "a.json");
      },
      Exit::preset, {"a.json", "'history_window' = 1", "at least 2"});
}

// Every numeric row of the table: its bounds are accepted, values beyond them are not.
TEST(Params, EveryRangeBoundIsInclusiveAndEnforced) {
  for (const ParamInfo& info : params_table()) {
    if (std::holds_alternative<bool Params::*>(info.member)) continue;
    const bool is_int = std::holds_alternative<int Params::*>(info.member);
    auto value = [&](double v) { return is_int ? json(int(v)) : json(v); };
    SCOPED_TRACE(info.key);
    EXPECT_NO_THROW(params_from_json(json{{info.key, value(info.min)}}, "min"));
    EXPECT_NO_THROW(params_from_json(json{{info.key, value(info.max)}}, "max"));
    const double above = is_int ? info.max + 1 : info.max * 2 + 1;
    const double below = is_int ? info.min - 1 : (info.min > 0 ? info.min / 2 : info.min - 1);
    expect_error(
        [&] {
          params_from_json(json{{info.key, value(above)}}, "above");
        },
        Exit::preset, {std::string("'") + info.key + "'", "out of range"});
    expect_error(
        [&] {
          params_from_json(json{{info.key, value(below)}}, "below");
        },
        Exit::preset, {std::string("'") + info.key + "'", "out of range"});
  }
}

TEST(Params, WrongTypeNamesKeyAndValue) {
  expect_error(
      [] {
        params_from_json(json{{"slices", 2.5}}, "t.json");
      },
      Exit::preset, {"t.json", "'slices'", "integer", "2.5"});
  expect_error(
      [] {
        params_from_json(json{{"radius", "big"}}, "t.json");
      },
      Exit::preset, {"'radius'", "number", "\"big\""});
  expect_error(
      [] {
        params_from_json(json{{"interleave", 1}}, "t.json");
      },
      Exit::preset, {"'interleave'", "true or false"});
  expect_error(
      [] {
        params_from_json(json{{"unseen_carry", 1}}, "t.json");
      },
      Exit::preset, {"'unseen_carry'", "true, false or \"auto\"", "1"});
  expect_error(
      [] {
        params_from_json(json{{"unseen_carry", "yes"}}, "t.json");
      },
      Exit::preset, {"'unseen_carry'", "\"yes\""});
  expect_error(
      [] {
        params_from_json(json{{"view_layer", 3}}, "t.json");
      },
      Exit::preset, {"'view_layer'", "string"});
  expect_error(
      [] {
        params_from_json(json{{"passes", {{"normal", 3}}}}, "t.json");
      },
      Exit::preset, {"'passes.normal'", "3"});
  expect_error(
      [] {
        params_from_json(json{{"passes", {{"normal", json::array()}}}}, "t.json");
      },
      Exit::preset, {"'passes.normal'"});
  expect_error(
      [] {
        params_from_json(json{{"emission", 1}}, "t.json");
      },
      Exit::preset, {"'emission'", "\"direct\"", "1"});
  expect_error(
      [] {
        params_from_json(json{{"emission", "both"}}, "t.json");
      },
      Exit::preset, {"'emission'", "\"both\"", "\"gathered\""});
  expect_error(
      [] {
        params_from_json(json{{"outputs", "ao"}}, "t.json");
      },
      Exit::preset, {"'outputs'", "array"});
  expect_error(
      [] {
        params_from_json(json{{"outputs", json::array({1})}}, "t.json");
      },
      Exit::preset, {"'outputs'", "strings"});
}

TEST(Params, UnknownOrMissingOutput) {
  expect_error(
      [] {
        params_from_json(json{{"outputs", json::array({"ao", "gi"})}}, "o.json");
      },
      Exit::preset, {"o.json", "unknown output 'gi'", "known: auto, ao, bentcone"});
  expect_error(
      [] {
        params_from_json(json{{"outputs", json::array()}}, "o.json");
      },
      Exit::preset, {"'outputs' is empty"});
}

// "auto" keeps explicit names (once, in their place) and adds the available auto outputs.
TEST(Params, ResolveAutoOutputs) {
  Params p;
  std::vector<std::string> dropped;
  auto geometry_only = [](const std::string& o) { return o == "ao" || o == "bentcone"; };
  EXPECT_EQ(resolve_outputs(p, geometry_only, &dropped).outputs,
            (std::vector<std::string>{"ao", "bentcone"}));
  EXPECT_EQ(dropped, (std::vector<std::string>{"irradiance", "indirect", "composite"}));
  EXPECT_EQ(resolve_outputs(p, [](const std::string&) { return true; }).outputs, auto_outputs());
  p.outputs = {"farfield", "auto", "ao"};
  EXPECT_EQ(resolve_outputs(p, geometry_only).outputs,
            (std::vector<std::string>{"farfield", "bentcone", "ao"}));
  p.outputs = {"indirect"};  // nothing to resolve: explicit outputs are kept as they are
  EXPECT_EQ(resolve_outputs(p, geometry_only).outputs, p.outputs);
}

TEST(Params, ApplySetPlainJsonAndDottedKeys) {
  Params base;
  base.slices = 4;
  const Params r = apply_set(base, "radius=0.5");
  EXPECT_EQ(r.radius, 0.5);
  EXPECT_EQ(r.slices, 4) << "other keys keep the base's value";
  EXPECT_EQ(base.radius, 1.0) << "the base is not modified";

  EXPECT_FALSE(apply_set(base, "interleave=false").interleave);
  EXPECT_EQ(apply_set(base, "steps=20").steps, 20);
  // A bare word is a string.
  EXPECT_EQ(apply_set(base, "view_layer=RenderLayer").view_layer, "RenderLayer");
  EXPECT_EQ(apply_set(base, "view_layer=\"Layer 2\"").view_layer, "Layer 2");
  // JSON values.
  EXPECT_EQ(apply_set(base, R"(outputs=["ao"])").outputs, std::vector<std::string>{"ao"});
  // Dotted keys reach into objects and leave the other fields alone.
  const Params d = apply_set(base, "passes.depth=Depth");
  EXPECT_EQ(d.passes.at("depth"), json("Depth"));
  EXPECT_EQ(d.passes.at("normal"), json("Normal"));
  const Params n = apply_set(base, R"(passes.normal=["N.x","N.y","N.z"])");
  EXPECT_EQ(n.passes.at("normal"), json::array({"N.x", "N.y", "N.z"}));
  EXPECT_EQ(n.passes.at("depth"), json("Depth"));
  EXPECT_EQ(apply_set(base, "passes.alpha=RenderLayer.Combined.A").passes.at("alpha"),
            json("RenderLayer.Combined.A"));
  // A value containing '=' keeps everything after the first one.
  EXPECT_EQ(apply_set(base, "view_layer=a=b").view_layer, "a=b");
}

TEST(Params, ApplySetErrorsNameTheAssignment) {
  const Params p;
  expect_error([&] { apply_set(p, "radius"); }, Exit::preset, {"--set radius", "key=value"});
  expect_error([&] { apply_set(p, "=3"); }, Exit::preset, {"key=value"});
  expect_error([&] { apply_set(p, "radius=-2"); }, Exit::preset,
               {"--set radius=-2", "'radius'", "-2", "out of range"});
  expect_error([&] { apply_set(p, "radus=2"); }, Exit::preset,
               {"--set radus=2", "unknown key 'radus'"});
  expect_error([&] { apply_set(p, "slices=many"); }, Exit::preset,
               {"'slices'", "integer", "\"many\""});
  expect_error([&] { apply_set(p, "passes.velocity=Vector"); }, Exit::preset, {"passes.velocity"});
  expect_error([&] { apply_set(p, R"(outputs=["ao","gi"])"); }, Exit::preset,
               {"unknown output 'gi'"});
  // Found by tests/fuzz/fuzz_preset: a bare word that is not UTF-8 (here Latin-1) made the
  // error message itself throw, and the tool answered "internal error".
  expect_error([&] { apply_set(p, "outputs=[\"ao\",\"composit\xce\"]"); }, Exit::preset,
               {"not valid UTF-8"});
  expect_error([&] { apply_set(p, "view_layer=Vi\xe9w"); }, Exit::preset, {"not valid UTF-8"});
  // Found by tests/fuzz/fuzz_preset: every dot nested the value once more, at a cost growing
  // with the square of the dots.
  expect_error([&] { apply_set(p, "passes.depth.x=Depth"); }, Exit::preset,
               {"unknown key 'passes.depth.x'", "at most one dot"});
}

// A preset file is refused with exit 7 naming it, whatever is wrong with its JSON. Found by
// tests/fuzz/fuzz_preset: a number beyond double's range (nlohmann's out_of_range, not a
// parse_error) escaped as "internal error".
TEST(Params, MalformedPresetFilesAreExit7NamingTheFile) {
  test::TempDir dir{test::test_name()};
  const std::string path = dir / "preset.json";
  for (const std::string text : {"{\"radius\": 1e999}", "{\"radius\": ", "[1, 2]", "\"\xff\""}) {
    SCOPED_TRACE(text);
    std::ofstream(path) << text;
    expect_error([&] { io::read_preset(path); }, Exit::preset, {path});
  }
  expect_error([&] { io::read_preset(dir / "missing.json"); }, Exit::preset, {"file not found"});
}

TEST(Params, ShippedPresetsLoad) {
  const fs::path dir = fs::path(HBIL_SOURCE_DIR) / "presets";
  std::vector<fs::path> files;
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(dir, ec))
    if (e.path().extension() == ".json") files.push_back(e.path());
  ASSERT_GE(files.size(), 4u) << "default, fast, quality, reference";
  for (const auto& f : files) {
    SCOPED_TRACE(f.string());
    json j;
    ASSERT_NO_THROW(j = json::parse(test::read_text(f))) << "not valid JSON";
    Params p;
    ASSERT_NO_THROW(p = params_from_json(j, f.string()));
    EXPECT_EQ(to_json(params_from_json(to_json(p), "round trip")), to_json(p));
  }
}

// presets/default.json is the full dump of the built-in defaults (`hbil preset --dump`): a
// default changed in params.h without the file (or the other way round) fails here.
TEST(Params, DefaultPresetIsTheFullDumpOfTheDefaults) {
  const json j = json::parse(test::read_text(fs::path(HBIL_SOURCE_DIR) / "presets/default.json"));
  EXPECT_EQ(j, to_json(Params{}));
}

// The man page documents every preset key with its default (".B key \fR= default").
TEST(Params, ManPageDocumentsEveryKeyWithItsDefault) {
  const std::string man = test::read_text(fs::path(HBIL_SOURCE_DIR) / "man/hbil.1");
  const json defaults = to_json(Params{});
  for (auto it = defaults.begin(); it != defaults.end(); ++it) {
    const std::string entry = ".B " + it.key() + " \\fR= ";
    const size_t at = man.find(entry);
    ASSERT_NE(at, std::string::npos) << "man/hbil.1 lacks " << entry;
    // The stated default parses to the built-in one (numbers: up to the unit or range).
    std::string text = man.substr(at + entry.size(), man.find('\n', at) - at - entry.size());
    // Numbers, booleans and "auto" (a number key derived from the shot) are followed by a range.
    if (it.value().is_number() || it.value().is_boolean() || it.value() == "auto")
      text = text.substr(0, text.find(' '));
    for (size_t q; (q = text.find("\\-")) != std::string::npos;) text.replace(q, 2, "-");
    // roff's \(dq is a quote that survives as a macro argument.
    for (size_t q; (q = text.find("\\(dq")) != std::string::npos;) text.replace(q, 4, "\"");
    const json stated = json::parse(text, nullptr, false);
    ASSERT_FALSE(stated.is_discarded()) << it.key() << ": " << text;
    if (it.value().is_number())
      EXPECT_DOUBLE_EQ(stated.get<double>(), it.value().get<double>()) << it.key();
    else
      EXPECT_EQ(stated, it.value()) << it.key();
  }
}

}  // namespace
}  // namespace hbil
