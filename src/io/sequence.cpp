// sequence.cpp: frame patterns, frame ranges and frame numbers in file names.
// Syntax and matching rules: see sequence.h.
#include "io/sequence.h"

#include <OpenImageIO/filesystem.h>

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cstdio>
#include <filesystem>
#include <regex>
#include <system_error>

#include "hbil/error.h"

namespace hbil::io {

namespace {

namespace fs = std::filesystem;

[[noreturn]] void pattern_error(const std::string& pattern, const std::string& why) {
  throw Error(Exit::usage, "frame pattern \"" + pattern + "\": " + why);
}

bool all_digits(std::string_view s) {
  return !s.empty() &&
         std::all_of(s.begin(), s.end(), [](unsigned char c) { return std::isdigit(c) != 0; });
}

// Int from a digit string, with a leading '-' when `negative_ok`; nullopt when it does not
// fit.
std::optional<int> to_int(std::string_view digits, bool negative_ok = false) {
  int v = 0;
  auto [end, ec] = std::from_chars(digits.data(), digits.data() + digits.size(), v);
  if (ec != std::errc() || end != digits.data() + digits.size() || (v < 0 && !negative_ok))
    return std::nullopt;
  return v;
}

}  // namespace

FramePattern::FramePattern(std::string pattern) : text_(std::move(pattern)) {
  // One pass over the text: collect the literal prefix, the frame field, the suffix.
  std::string literal;
  bool have_field = false;
  size_t field_end_in_text = 0;
  const std::string& s = text_;
  for (size_t i = 0; i < s.size();) {
    if (s[i] == '#' || s[i] == '@') {
      size_t j = i;
      while (j < s.size() && s[j] == s[i]) ++j;
      if (have_field) pattern_error(s, "more than one frame field ('#', '@' or '%d')");
      have_field = true;
      prefix_ = literal;
      literal.clear();
      pad_ = int(j - i);
      field_end_in_text = j;
      i = j;
    } else if (s[i] == '%') {
      if (i + 1 < s.size() && s[i + 1] == '%') {  // "%%": literal percent sign
        literal += '%';
        i += 2;
        continue;
      }
      // "%d" or "%0Nd".
      size_t j = i + 1;
      int width = 0;
      if (j < s.size() && s[j] == '0') {
        ++j;
        const size_t digits_start = j;
        while (j < s.size() && std::isdigit(static_cast<unsigned char>(s[j]))) ++j;
        if (j == digits_start || j - digits_start > 2)
          pattern_error(s, "expected %d or %0Nd (N = 1..99) at \"" + s.substr(i) + "\"");
        width = std::stoi(s.substr(digits_start, j - digits_start));
      }
      if (j >= s.size() || s[j] != 'd')
        pattern_error(s, "only %d and %0Nd are allowed (use %% for a literal '%'), found \"" +
                             s.substr(i, std::min<size_t>(4, s.size() - i)) + "\"");
      if (have_field) pattern_error(s, "more than one frame field ('#', '@' or '%d')");
      have_field = true;
      prefix_ = literal;
      literal.clear();
      pad_ = width;
      field_end_in_text = j + 1;
      i = j + 1;
    } else {
      literal += s[i++];
    }
  }
  if (!have_field) {
    prefix_ = literal;  // unescaped "%%"
    suffix_.clear();
    pad_ = 0;
    is_sequence_ = false;
    return;
  }
  suffix_ = literal;
  is_sequence_ = true;
  if (suffix_.find('/') != std::string::npos || suffix_.find('\\') != std::string::npos ||
      s.find('/', field_end_in_text) != std::string::npos)
    pattern_error(s, "the frame field must be in the file name, not in a directory name");
}

std::string FramePattern::path(int frame) const {
  if (!is_sequence_) return prefix_;
  char buf[32];
  std::snprintf(buf, sizeof buf, "%0*d", pad_, frame);  // same as Blender's BLI_path_frame
  return prefix_ + buf + suffix_;
}

std::vector<int> FramePattern::existing_frames() const {
  std::vector<int> frames;
  std::error_code ec;
  if (!is_sequence_) {
    if (fs::is_regular_file(prefix_, ec))
      frames.push_back(frame_number_from_name(prefix_).value_or(0));
    return frames;
  }
  const fs::path prefix_path(prefix_);
  // prefix_ = "<dir>/<name start>"; a prefix ending in '/' has an empty name start.
  const bool ends_with_sep = !prefix_.empty() && (prefix_.back() == '/');
  const fs::path dir = ends_with_sep ? prefix_path : prefix_path.parent_path();
  const std::string name_start = ends_with_sep ? "" : prefix_path.filename().string();
  const std::string dir_prefix = prefix_.substr(0, prefix_.size() - name_start.size());
  fs::directory_iterator it(dir.empty() ? fs::path(".") : dir, ec);
  if (ec) return frames;
  for (const fs::directory_entry& entry : it) {
    if (!entry.is_regular_file(ec)) continue;
    const std::string name = entry.path().filename().string();
    if (name.size() <= name_start.size() + suffix_.size()) continue;
    if (name.compare(0, name_start.size(), name_start) != 0) continue;
    if (name.compare(name.size() - suffix_.size(), suffix_.size(), suffix_) != 0) continue;
    const std::string_view digits = std::string_view(name).substr(
        name_start.size(), name.size() - name_start.size() - suffix_.size());
    const bool minus = !digits.empty() && digits.front() == '-';
    if (!all_digits(minus ? digits.substr(1) : digits)) continue;
    const std::optional<int> frame = to_int(digits, true);
    // The file is frame n exactly when formatting n gives its name back (padding rules).
    if (frame && path(*frame) == dir_prefix + name) frames.push_back(*frame);
  }
  std::sort(frames.begin(), frames.end());
  frames.erase(std::unique(frames.begin(), frames.end()), frames.end());
  return frames;
}

std::vector<int> parse_frame_list(const std::string& text, const std::string& option) {
  const auto fail = [&](const std::string& why) {
    throw Error(Exit::usage, option + ": \"" + text + "\": " + why +
                                 " (expected frames as oiiotool takes them: 12, 1-100, 1-100x2, "
                                 "1,3,5-8, -5--1)");
  };
  if (text.empty()) fail("no frames");
  // Each item is checked here, so that OpenImageIO (which reads what it can of a malformed
  // item) is only given what it reads exactly, and no list holds more than kMaxFrames.
  static const std::regex item_syntax(R"((-?\d+)(?:-(-?\d+)(?:([xy])(\d+))?)?)");
  long long count = 0;
  size_t begin = 0;
  for (;;) {
    const size_t comma = text.find(',', begin);
    const std::string item = text.substr(begin, comma == std::string::npos ? comma : comma - begin);
    std::smatch m;
    // (std::regex recurses per character: a long item is refused before it is matched.)
    if (item.size() > 40 || !std::regex_match(item, m, item_syntax))
      fail(item.empty() ? "an empty item" : "\"" + item + "\" is not a frame or a range");
    const std::optional<int> a = to_int(m.str(1), true);
    const std::optional<int> b = m[2].matched ? to_int(m.str(2), true) : a;
    const std::optional<int> step = m[4].matched ? to_int(m.str(4)) : 1;
    const auto in_range = [](std::optional<int> f) {
      return f && std::abs((long long)(*f)) <= kMaxFrame;
    };
    if (!in_range(a) || !in_range(b))
      fail("a frame number in \"" + item + "\" is beyond +-" + std::to_string(kMaxFrame));
    if (!step || *step < 1) fail("the step in \"" + item + "\" must be a positive number");
    count += std::abs((long long)(*b) - *a) + 1;
    if (count > kMaxFrames) fail("more than " + std::to_string(kMaxFrames) + " frames");
    if (comma == std::string::npos) break;
    begin = comma + 1;
  }
  std::vector<int> frames;
  if (!OIIO::Filesystem::enumerate_sequence(text, frames)) fail("not a frame list");
  std::sort(frames.begin(), frames.end());
  frames.erase(std::unique(frames.begin(), frames.end()), frames.end());
  if (frames.empty()) fail("no frames");  // "1-2y1": the complement of every frame
  return frames;
}

std::string format_frame_list(const std::vector<int>& f) {
  std::string out;
  for (size_t a = 0; a < f.size();) {
    size_t b = a;
    if (a + 1 < f.size()) {
      const long long step = (long long)(f[a + 1]) - f[a];
      while (b + 1 < f.size() && (long long)(f[b + 1]) - f[b] == step) ++b;
      // A run of two with a step is two frames, not a range.
      if (step != 1 && b == a + 1) b = a;
    }
    if (!out.empty()) out += ',';
    out += std::to_string(f[a]);
    if (b > a) {
      out += '-';
      out += std::to_string(f[b]);
      if (f[a + 1] - f[a] != 1) {
        out += 'x';
        out += std::to_string(f[a + 1] - f[a]);
      }
    }
    a = b + 1;
  }
  return out;
}

std::optional<int> frame_number_from_name(const std::string& path) {
  const std::string stem = fs::path(path).stem().string();
  size_t end = stem.size();
  while (end > 0 && !std::isdigit(static_cast<unsigned char>(stem[end - 1]))) --end;
  if (end == 0) return std::nullopt;
  size_t begin = end;
  while (begin > 0 && std::isdigit(static_cast<unsigned char>(stem[begin - 1]))) --begin;
  return to_int(std::string_view(stem).substr(begin, end - begin));
}

}  // namespace hbil::io
