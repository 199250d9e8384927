// sky.pov: a sky whose colour codes its direction, ((x, y, z) + 1) / 2 in POV-Ray space, and
// two objects that the sky pass must hide (one converted, one not), for tests/povray_test.cpp
// (PovraySky). Rendered with
//   samples/povray/render_gbuffer.sh --sky 64x32 --size 32x18 --no-import \
//     tests/data/povray_sky/sky.pov /tmp/sky
// and /tmp/sky/sky.exr copied here.
#version 3.7;
#include "hbil.inc"
HBIL_Camera(<0, 1, -3>, <0, 1, 0>, 60)
HBIL_Sky(pigment { average pigment_map {
  [ function { (x + 1) / 2 } color_map { [0 rgb 0] [1 rgb <3, 0, 0>] } ]
  [ function { (y + 1) / 2 } color_map { [0 rgb 0] [1 rgb <0, 3, 0>] } ]
  [ function { (z + 1) / 2 } color_map { [0 rgb 0] [1 rgb <0, 0, 3>] } ] } })
sphere { <0, 1, 0>, 1.5 HBIL_Matte(pigment { rgb 0.5 }) }
box { <-10, -1, -10>, <10, 0, 10> }
