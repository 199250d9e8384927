// room.pov: hbil's POV-Ray sample. A room open at the front (red and green side walls for
// colour bleeding), lit by the sun through a window and a small emissive ceiling panel, with thin objects:
// a 2 cm standing panel and two 5 cm poles. The camera dollies and pans over frames 1-6.
// Units are metres; POV-Ray space: +y up, left-handed. Render with render_gbuffer.sh:
//   samples/povray/render_gbuffer.sh --frames 1-6 --size 256x144 --reference \
//     samples/povray/room.pov /tmp/pov_room
#version 3.7;
#include "hbil.inc"

#declare T = (frame_number - 1) / 5;
HBIL_Camera(<-0.9 + 0.6 * T, 1.5 + 0.05 * T, -2.4 + 0.15 * T>, <0.0 + 0.3 * T, 0.7, 1.0>, 70)

#declare White = pigment { rgb 0.75 };
// Room: interior x in [-2, 2], y in [0, 2.8], z in [-2.5, 2]; walls 10 cm thick; the
// front (z = -2.5) is open. The red left wall has a 1.2 m square window.
box { <-2.1, -0.1, -2.5>, <2.1, 0, 2.1> HBIL_Matte(pigment { rgb 0.6 }) }        // floor
box { <-2.1, 2.8, -2.5>, <2.1, 2.9, 2.1> HBIL_Matte(pigment { rgb 0.8 }) }        // ceiling
difference {                                                                        // left
  box { <-2.1, 0, -2.5>, <-2, 2.8, 2.1> }
  box { <-2.2, 0.9, -0.2>, <-1.9, 2.1, 1.0> }
  HBIL_Matte(pigment { rgb <0.8, 0.1, 0.08> })
}
box { <2, 0, -2.5>, <2.1, 2.8, 2.1> HBIL_Matte(pigment { rgb <0.1, 0.7, 0.12> }) }   // right
box { <-2, 0, 2>, <2, 2.8, 2.1> HBIL_Matte(White) }                                 // back

// Thin objects: a 2 cm panel and two poles of 2.5 cm radius, floor to ceiling.
box { <-0.5, 0, 1.2>, <0.5, 1.6, 1.22> HBIL_Matte(pigment { rgb <0.8, 0.7, 0.3> }) }
cylinder { <0.6, 0, 0.2>, <0.6, 2.8, 0.2>, 0.025 HBIL_Matte(White) }
cylinder { <1.0, 0, 0.7>, <1.0, 2.8, 0.7>, 0.025 HBIL_Matte(White) }
// A blue block and a white ball.
box { <-0.4, 0, -0.35>, <0.4, 0.6, 0.35> rotate y * 20 translate <1.2, 0, 1.3>
      HBIL_Matte(pigment { rgb <0.15, 0.25, 0.8> }) }
sphere { <-0.9, 0.4, -0.3>, 0.4 HBIL_Matte(White) }

// Sunlight through the window onto the floor, and a warm emissive ceiling panel.
light_source { <-2, 1.5, 0.4> - 20 * <0.78, -0.6, 0.15>, rgb 3 parallel point_at <-2, 1.5, 0.4> }
box { <0.8, 2.78, -1.0>, <1.4, 2.8, -0.4> HBIL_Emitter(rgb <3, 2.4, 1.6>) }
