// frame_output.cpp: see frame_output.h.
#include "pipeline/frame_output.h"

#include <OpenImageIO/imageio.h>

#include <algorithm>
#include <cinttypes>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <future>

#include "hbil/error.h"
#include "io/exr_frame.h"

namespace hbil::pipeline {

namespace fs = std::filesystem;

namespace {

// The pixels of a display layer: 1 (ao), 3 or 4 (composite) channels; the frame's own
// buffer where it is stored that way, else `scratch` filled.
const std::vector<float>& display_pixels(const AoFrame& f, const std::string& layer, int& channels,
                                         std::vector<float>& scratch) {
  const size_t n = size_t(f.width) * f.height;
  if (layer == "composite") {
    channels = 4;
    scratch.resize(n * 4);
    for (size_t i = 0; i < n; ++i) {
      const Vec3& c = f.composite[i];
      float* px = &scratch[4 * i];
      px[0] = c.x, px[1] = c.y, px[2] = c.z;
      px[3] = f.composite_alpha.empty() ? 1.f : f.composite_alpha[i];
    }
    return scratch;
  }
  if (layer == "ao" && f.ao_rgb.empty()) {
    channels = 1;
    return f.ao;
  }
  const std::vector<Vec3>& v = layer == "ao"           ? f.ao_rgb
                               : layer == "irradiance" ? f.irradiance
                               : layer == "indirect"   ? f.indirect
                                                       : f.farfield;
  channels = 3;
  scratch.resize(n * 3);
  for (size_t i = 0; i < n; ++i)
    scratch[3 * i] = v[i].x, scratch[3 * i + 1] = v[i].y, scratch[3 * i + 2] = v[i].z;
  return scratch;
}

// The display image frames the display window: the data window's pixels where the two
// overlap, zero (black; transparent where there is alpha) where the data window has none,
// and the guard band beyond the display window left out. `px` itself where the windows are
// one (or `spec` is not the frame's), else `scratch` filled.
const std::vector<float>& display_window(const std::vector<float>& px, int channels, int& width,
                                         int& height, const OIIO::ImageSpec& spec,
                                         std::vector<float>& scratch) {
  if (spec.width != width || spec.height != height || !io::windowed(spec) || spec.full_width <= 0 ||
      spec.full_height <= 0)
    return px;
  const int w = spec.full_width, h = spec.full_height;
  std::vector<float> out(size_t(w) * size_t(h) * size_t(channels), 0.f);
  for (int y = 0; y < h; ++y) {
    const int sy = y + spec.full_y - spec.y;  // the data window's row
    if (sy < 0 || sy >= height) continue;
    for (int x = 0; x < w; ++x) {
      const int sx = x + spec.full_x - spec.x;
      if (sx < 0 || sx >= width) continue;
      const float* from = &px[(size_t(sy) * size_t(width) + size_t(sx)) * size_t(channels)];
      std::copy(from, from + channels,
                &out[(size_t(y) * size_t(w) + size_t(x)) * size_t(channels)]);
    }
  }
  scratch = std::move(out);
  width = w;
  height = h;
  return scratch;
}

// 64-bit FNV-1a over fields, each preceded by its length so that no two lists of fields
// hash the same bytes.
class Digest {
 public:
  Digest& add(const std::string& field) {
    const uint64_t n = field.size();
    mix(&n, sizeof n);
    mix(field.data(), field.size());
    return *this;
  }
  std::string hex() const {
    char text[17];
    std::snprintf(text, sizeof text, "%016" PRIx64, h_);
    return text;
  }

 private:
  void mix(const void* data, size_t size) {
    for (size_t i = 0; i < size; ++i) {
      h_ ^= static_cast<const unsigned char*>(data)[i];
      h_ *= 0x100000001b3ull;
    }
  }
  uint64_t h_ = 0xcbf29ce484222325ull;
};

// A file as the job digest sees it: its name (not its folder, which a farm host may mount
// elsewhere), size and modification time; "missing" when it cannot be looked at.
std::string file_identity(const std::string& path) {
  std::error_code ec, ec2;
  const auto size = fs::file_size(path, ec);
  const auto time = fs::last_write_time(path, ec2);
  if (ec || ec2) return fs::path(path).filename().string() + " missing";
  return fs::path(path).filename().string() + " " + std::to_string(size) + " " +
         std::to_string(time.time_since_epoch().count());
}

// Whether an image file opens and its first and last rows read (a file cut short loses its
// last rows first); `why` says what failed. `job`: receives its hbil:job attribute.
bool reads_whole(const std::string& path, std::string& why, std::string* job = nullptr) {
  std::error_code ec;
  if (!fs::is_regular_file(path, ec)) {
    why = path + " is missing";
    return false;
  }
  auto in = OIIO::ImageInput::open(path);
  if (!in) {
    OIIO::geterror();  // not kept for a later message
    why = path + " does not open";
    return false;
  }
  const OIIO::ImageSpec& spec = in->spec();
  if (job) *job = spec.get_string_attribute("hbil:job");
  std::vector<float> row(size_t(std::max(spec.width, 1)) * size_t(std::max(spec.nchannels, 1)));
  for (int y : {spec.y, spec.y + spec.height - 1})
    if (!in->read_scanline(y, 0, OIIO::TypeDesc::FLOAT, row.data())) {
      in->geterror();
      why = path + ": row " + std::to_string(y) + " does not read";
      return false;
    }
  return true;
}

}  // namespace

std::string shipped_ocio_config() {
  std::error_code ec;
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  const fs::path installed = exe.parent_path().parent_path() / "share/hbil/ocio/hbil.ocio";
  if (!ec && fs::exists(installed)) return installed.string();
  return HBIL_OCIO_CONFIG;
}

FrameOutput::FrameOutput(const OutputSettings& s, const SequenceJob& job)
    : out_(s.output), p_(job.params()) {
  const SequencePlan& plan = job.plan();
  if (plan.frames.size() > 1 && !out_.is_sequence())
    throw Error(Exit::usage, "-o " + s.output + ": a sequence of " +
                                 std::to_string(plan.frames.size()) +
                                 " frames needs an output frame pattern (e.g. out/frame_####.exr)");
  for (int f : plan.frames) {
    std::error_code ec;
    if (fs::equivalent(plan.input.path(f), out_.path(f), ec))
      throw Error(Exit::usage, "-o " + out_.path(f) + " would overwrite its own input");
  }
  // Without --display-out, a PNG of the composite (or of --display-layer) goes beside each
  // EXR, unless --no-display.
  display_layer_ = s.display_layer;
  display_out_ = s.display_out;
  if (display_out_.empty() && !s.no_display && (p_.wants("composite") || !display_layer_.empty()))
    display_out_ = fs::path(s.output).replace_extension(".png").string();
  if (!display_out_.empty() && s.no_display)
    throw Error(Exit::usage, "--display-out and --no-display contradict each other");
  if (!display_out_.empty()) {
    if (!io::is_display_image_path(display_out_))
      throw Error(Exit::usage,
                  "--display-out " + display_out_ + ": use a .png, .jpg, .jpeg or .exr name");
    if (display_layer_.empty())
      display_layer_ = p_.wants("composite") ? "composite" : p_.outputs.front();
    if (display_layer_ == "bentcone" || display_layer_ == "history" || !p_.wants(display_layer_))
      throw Error(Exit::usage,
                  "--display-layer " + display_layer_ +
                      ": must be one of the computed colour layers (ao, irradiance, indirect, "
                      "farfield, composite) named in outputs");
    io::DisplaySettings d = s.display;
    if (d.input_space.empty()) d.input_space = p_.input_space;
    display_.emplace(d, shipped_ocio_config());
    display_pattern_.emplace(display_out_);
    if (plan.frames.size() > 1 && !display_pattern_->is_sequence())
      throw Error(Exit::usage,
                  "--display-out " + display_out_ + ": a sequence needs a frame pattern");
    for (int f : plan.frames)
      if (display_pattern_->path(f) == out_.path(f))
        throw Error(Exit::usage, "--display-out " + display_out_ + " is the EXR output's name");
  }
  for (int f : plan.frames) {
    batch_.expect(out_.path(f));
    if (display_pattern_) batch_.expect(display_pattern_->path(f));
    for (const std::string& file :
         {out_.path(f), display_pattern_ ? display_pattern_->path(f) : out_.path(f)}) {
      std::string dir = fs::path(file).parent_path().string();
      if (dir.empty()) dir.assign(1, '.');  // not = ".": GCC 12 -Wrestrict false positive
      if (std::find(folders_.begin(), folders_.end(), dir) == folders_.end())
        folders_.push_back(dir);
    }
  }
  // Job digests: what every frame has in common, then its inputs.
  Digest common;
  common.add(HBIL_VERSION).add(to_json(p_).dump());
  if (display_) common.add(display_layer_).add(display_->describe());  // not its folder
  for (int cut : plan.cuts) common.add(std::to_string(cut));
  if (!p_.environment.empty()) common.add(file_identity(p_.environment));
  const bool chained = p_.temporal && plan.preroll.size() + plan.frames.size() > 1;
  Digest chain = common;
  for (int f : plan.preroll) chain.add(file_identity(plan.input.path(f)));
  for (int f : plan.frames) {
    const std::string input = file_identity(plan.input.path(f));
    chain.add(input);
    jobs_[f] = chained ? chain.hex() : Digest(common).add(input).hex();
  }
}

bool FrameOutput::done(int frame, std::string* why) const {
  std::string reason, made;
  bool ok = reads_whole(out_.path(frame), reason, &made);
  if (ok) {
    if (made != job(frame)) {
      ok = false;
      reason =
          out_.path(frame) + (made.empty() ? " was not made by hbil --skip-existing's rules"
                                           : " was made by other settings or from other inputs");
    }
  }
  if (ok && display_pattern_) ok = reads_whole(display_pattern_->path(frame), reason);
  if (!ok && why) *why = reason;
  return ok;
}

int FrameOutput::remove_stale() const {
  int n = 0;
  for (const std::string& dir : folders_) n += io::remove_stale_temporaries(dir);
  return n;
}

std::string FrameOutput::describe_display() const {
  if (!display_) return "";
  return display_out_ + " (" + display_layer_ + "): " + display_->describe();
}

void FrameOutput::write(const FrameResult& r, const std::function<void()>& committed) {
  const std::string out_path = out_.path(r.frame);
  // The display image is written beside the EXR, on a thread of its own (PNG's deflate runs
  // on one core). Whatever either write leaves goes into the batch before an error is
  // passed on, so that the failing frame leaves nothing.
  std::future<std::string> shown;
  const std::string shown_path = display_ ? display_pattern_->path(r.frame) : "";
  if (display_)
    shown = std::async(std::launch::async, [&] {
      int channels = 0;
      std::vector<float> scratch, framed;
      int width = r.outputs.width, height = r.outputs.height;
      const std::vector<float>& layer =
          display_pixels(r.outputs, display_layer_, channels, scratch);
      const std::vector<float>& px =
          display_window(layer, channels, width, height, r.input->spec, framed);
      return io::write_display_temporary(
          shown_path, px, channels, width, height, *display_,
          "hbil " + display_layer_ + ", frame " + std::to_string(r.frame));
    });
  std::exception_ptr failed;
  try {
    batch_.add(io::write_temporary(out_path, r.outputs, r.input->spec, p_, r.camera, r.frame,
                                   job(r.frame)),
               out_path);
  } catch (...) {
    failed = std::current_exception();
  }
  if (shown.valid()) {
    try {
      batch_.add(shown.get(), shown_path);
    } catch (...) {
      if (!failed) failed = std::current_exception();
    }
  }
  if (failed) {
    batch_.discard();
    std::rethrow_exception(failed);
  }
  {
    const io::FrameCommit whole;  // an interrupt waits until the frame is in place and noted
    batch_.commit();              // the EXR, then the display image
    io::note_frame_written(r.frame);
    written_.push_back(r.frame);
    if (committed) committed();
  }
}

}  // namespace hbil::pipeline
