// analytic.pov: a tilted plane and a sphere under a sky, for tests/povray_test.cpp, which
// intersects the same two surfaces in closed form and checks hbil import-povray's depth,
// normals and camera against them. Rendered (128x72, depth and normal passes) with
//   samples/povray/render_gbuffer.sh --size 128x72 --passes depth,normal --no-import \
//     tests/data/povray_analytic/analytic.pov /tmp/analytic
// and the passes and camera1.json copied here. Its panorama (panorama/: the distance from the
// camera's location over the whole sphere, 64x32) with
//   samples/povray/render_gbuffer.sh --size 128x72 --passes depth,normal --panorama 64x32 \
//     --no-import tests/data/povray_analytic/analytic.pov /tmp/analytic
// and passes/panorama/depth1.exr and camera1.json copied to panorama/.
#version 3.7;
#include "hbil.inc"
HBIL_Camera(<0.3, 1.5, -4>, <0, 1, 0>, 60)
// 0.2 x + y - 0.05 z = -0.2 (the plane's normal is not normalised here; POV-Ray does).
plane { <0.2, 1, -0.05>, -0.2 / vlength(<0.2, 1, -0.05>) HBIL_Matte(pigment { rgb 0.5 }) }
sphere { <0.5, 1.2, 0.5>, 0.8 HBIL_Matte(pigment { rgb 0.5 }) }
