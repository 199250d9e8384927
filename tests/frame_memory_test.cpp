// frame_memory_test.cpp: what `hbil run` does to hold less of a frame in memory changes no
// value: colour fields kept as half bits until they are used (GBuffer::packed), the
// temporal chain releasing each input field after its last use, and the outputs made over
// the search's buffers.

#include <Imath/half.h>
#include <gtest/gtest.h>

#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include "hbil/error.h"
#include "hbil/gbuffer.h"
#include "hbil/temporal.h"
#include "io/camera_io.h"
#include "io/exr_frame.h"
#include "test_util.h"

namespace hbil {
namespace {

template <class T>
bool same_bytes(const std::vector<T>& a, const std::vector<T>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(T)) == 0;
}

TEST(HalfToFloat, EveryBitPatternGivesOpenExrsFloat) {
  for (uint32_t b = 0; b <= 0xffff; ++b) {
    Imath::half h;
    h.setBits(uint16_t(b));
    const float want = float(h), got = half_to_float(uint16_t(b));
    uint32_t wb, gb;
    std::memcpy(&wb, &want, 4);
    std::memcpy(&gb, &got, 4);
    ASSERT_EQ(wb, gb) << "half bits 0x" << std::hex << b;
  }
}

struct Input {
  GBuffer g;
  Camera cam;
};

Input read_sample(int frame, bool keep_half) {
  Params p;
  const std::string path = test::kRoomPoles + "/frame_000" + std::to_string(frame) + ".exr";
  const io::InputFrame in = io::open_frame(path, frame, p);
  Input r;
  r.g = io::read_fields(in, io::fields_needed(in, p), p, keep_half);
  r.cam = io::find_camera(in, r.g, p);
  return r;
}

// Frames 1-3 of the sample through two chains: one given each G-buffer to keep (floats), one
// given it to release (packed, as `hbil run` reads it). Every output is the same to the bit.
TEST(FrameMemory, ReleasingChainGivesTheKeepingChainsBytes) {
  Params p;
  p.outputs = {"ao", "bentcone", "irradiance", "indirect", "composite", "history"};
  TemporalChain keep(p), release(p);
  for (int frame = 1; frame <= 3; ++frame) {
    SCOPED_TRACE(frame);
    const Input a = read_sample(frame, false);
    Input b = read_sample(frame, true);
    ASSERT_FALSE(b.g.packed.empty());
    const AoFrame fa = keep.process(a.g, a.cam, frame, false);
    const AoFrame fb = release.process(std::move(b.g), b.cam, frame, false);
    EXPECT_TRUE(b.g.diffdir.empty() && b.g.depth.empty() && b.g.motion.empty())
        << "the fields were released";
    EXPECT_TRUE(same_bytes(fa.ao, fb.ao));
    EXPECT_TRUE(same_bytes(fa.cone_cos, fb.cone_cos));
    EXPECT_TRUE(same_bytes(fa.bent, fb.bent));
    EXPECT_TRUE(same_bytes(fa.irradiance, fb.irradiance));
    EXPECT_TRUE(same_bytes(fa.indirect, fb.indirect));
    EXPECT_TRUE(same_bytes(fa.composite, fb.composite));
    EXPECT_TRUE(same_bytes(fa.composite_alpha, fb.composite_alpha));
    EXPECT_TRUE(same_bytes(fa.history, fb.history));
    ASSERT_EQ(fa.composite.size(), a.g.pixels());
    EXPECT_EQ(fa.history.size(), a.g.pixels());
  }
}

TEST(FrameMemory, KeepingChainRefusesAPackedGBuffer) {
  const Input b = read_sample(1, true);
  TemporalChain chain{Params{}};
  test::expect_error([&] { chain.process(b.g, b.cam, 1, false); }, Exit::failure, {"packed"});
}

}  // namespace
}  // namespace hbil
