// study.pov: a second POV-Ray scene, written as a user would convert one, and never used
// for tuning (README "POV-Ray", held-out row). A study with a checkered floor, a shelf of
// 2 cm boards, a table with a thin top and legs, a window to a sky, the sun through it and a
// lamp. The camera pans and rises over frames 1-8. Not committed as renders; to measure:
//   samples/povray/render_gbuffer.sh --frames 1-8 --size 320x180 --reference --sky 512x256 \
//     samples/povray/study.pov /tmp/pov_study
//   samples/povray/render_gbuffer.sh --frames 1-8 --size 320x180 --reference --bounces 1 \
//     --no-import samples/povray/study.pov /tmp/pov_study_b1
//   grep -v '^HBIL_Sky' samples/povray/study.pov > /tmp/study_nosky.pov   # the sky's share
//   samples/povray/render_gbuffer.sh --frames 1-8 --size 320x180 --reference --bounces 1 \
//     /tmp/study_nosky.pov /tmp/pov_nosky
//   ONLY_POVRAY=1 HELDOUT_POV=/tmp/pov_study HELDOUT_POV_NOSKY=/tmp/pov_nosky bench/tables.sh
// (render_gbuffer.sh finds hbil.inc on its own library path.)
#version 3.7;
#include "hbil.inc"

#declare T = (frame_number - 1) / 7;
HBIL_Camera(<-1.2 + 1.4 * T, 1.3 + 0.3 * T, -2.6>, <0.4 * T - 0.2, 0.9, 1.5>, 65)
HBIL_Sky(pigment { gradient y color_map { [0 rgb <0.9, 0.95, 1.0>] [1 rgb <0.35, 0.5, 0.9>] } })

// Room x in [-2.5, 2.5], y in [0, 2.6], z in [-3, 2]; the wall behind the camera is open.
#declare Plaster = pigment { rgb <0.78, 0.76, 0.72> };
box { <-2.6, -0.1, -3>, <2.6, 0, 2.1>
      HBIL_Matte(pigment { checker rgb <0.55, 0.35, 0.2>, rgb <0.7, 0.55, 0.35> scale 0.5 }) }
box { <-2.6, 2.6, -3>, <2.6, 2.7, 2.1> HBIL_Matte(Plaster) }
box { <-2.6, 0, -3>, <-2.5, 2.6, 2.1> HBIL_Matte(pigment { rgb <0.2, 0.3, 0.65> }) }
difference {  // right wall with a window
  box { <2.5, 0, -3>, <2.6, 2.6, 2.1> }
  box { <2.4, 0.8, -1.2>, <2.7, 2.2, 0.4> }
  HBIL_Matte(Plaster)
}
box { <-2.5, 0, 2>, <2.5, 2.6, 2.1> HBIL_Matte(Plaster) }

// Shelf against the back wall: two 2 cm sides and four 2 cm boards.
#declare Wood = pigment { rgb <0.6, 0.42, 0.25> };
union {
  box { <-1.8, 0, 1.6>, <-1.78, 2.0, 2.0> }
  box { <-0.62, 0, 1.6>, <-0.6, 2.0, 2.0> }
  #for (I, 0, 3)
    box { <-1.78, 0.3 + 0.55 * I, 1.6>, <-0.62, 0.32 + 0.55 * I, 2.0> }
  #end
  HBIL_Matte(Wood)
}
// Table: 3 cm top, four 4 cm legs.
union {
  box { <0.2, 0.72, 0.0>, <1.6, 0.75, 0.9> }
  #for (X, 0, 1) #for (Z, 0, 1)
    box { <0.25 + 1.26 * X, 0, 0.05 + 0.76 * Z>, <0.29 + 1.26 * X, 0.72, 0.09 + 0.76 * Z> }
  #end #end
  HBIL_Matte(pigment { rgb <0.85, 0.85, 0.8> })
}
sphere { <0.9, 0.95, 0.45>, 0.2 HBIL_Matte(pigment { rgb <0.8, 0.2, 0.15> }) }
cylinder { <-1.5, 0, -0.5>, <-1.5, 1.1, -0.5>, 0.3 HBIL_Matte(pigment { rgb 0.7 }) }

// The sun through the window, and a lamp under the ceiling.
light_source { <2.5, 1.5, -0.4> + 20 * <0.7, 0.55, -0.2>, rgb 2.5
               parallel point_at <2.5, 1.5, -0.4> }
light_source { <-0.5, 2.3, 0.5>, rgb <0.5, 0.45, 0.35> }
