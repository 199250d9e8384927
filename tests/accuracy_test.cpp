// accuracy_test.cpp: AO against the Cycles AO pass of the Blender samples (samples/README.md:
// 512 spp, World > Ambient Occlusion > Distance 1.0 = the default radius). Same measure as
// `hbil compare --layer ao --ref-layer AO`: PSNR (peak 1) over pixels with depth < 1e9, all 8
// frames. Bounds sit just below what the default preset measures (README "Accuracy"); a
// change that loses more than ~0.3 dB fails here.
#include <OpenImageIO/imageio.h>
#include <gtest/gtest.h>

#include "hbil/ao_frame.h"
#include "hbil/error_stats.h"
#include "io/exr_frame.h"
#include "io/sequence.h"

namespace hbil {
namespace {

ErrorStats ao_error(const std::string& scene, const Params& p) {
  ErrorStats all;
  const io::FramePattern pattern(std::string(HBIL_SOURCE_DIR) + "/samples/" + scene +
                                 "/frame_####.exr");
  for (int frame = 1; frame <= 8; ++frame) {
    const io::InputFrame in = io::open_frame(pattern.path(frame), frame, p);
    GBuffer g = io::read_fields(in, io::fields_needed(in, p), p);
    const AoFrame f = compute_ao_frame(g, io::find_camera(in, g, p), p);
    auto img = OIIO::ImageInput::open(in.path);
    const int c = in.spec.channelindex("ViewLayer.AO.R");
    EXPECT_GE(c, 0);
    std::vector<float> ref(g.pixels());
    EXPECT_TRUE(img->read_image(0, 0, c, c + 1, OIIO::TypeDesc::FLOAT, ref.data()));
    for (size_t i = 0; i < g.pixels(); ++i)
      if (g.depth[i] < 1e9f) all.add(f.ao[i], ref[i]);
  }
  return all;
}

TEST(AccuracyAgainstCycles, CourtyardAo) {
  const ErrorStats e = ao_error("courtyard", Params{});
  EXPECT_GT(e.count, 200000u);
  EXPECT_GT(e.psnr(), 20.2) << "rmse " << e.rmse() << " mean "
                            << e.mean_error();  // measured 20.51 dB
}

// Horizon-based AO over-darkens behind thin objects (the wall behind the fence, the floor
// around the poles): the heightfield it assumes makes every slat infinitely thick. That
// error is local; over the whole frame hbil is brighter than Cycles on average (+0.019).
TEST(AccuracyAgainstCycles, RoomWithPolesAo) {
  const ErrorStats e = ao_error("room_poles", Params{});
  EXPECT_GT(e.count, 200000u);
  EXPECT_GT(e.psnr(), 18.3) << "rmse " << e.rmse() << " mean "
                            << e.mean_error();  // measured 18.56 dB
}

}  // namespace
}  // namespace hbil
