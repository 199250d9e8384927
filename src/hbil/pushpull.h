// pushpull.h: depth-aware push/pull hole filling (after Kraus 2009, "The Pull-Push
// Algorithm Revisited"), for the disocclusions and splat gaps reprojection leaves behind.
//
// The image is `channels` floats per pixel, rows top-down, pixel-major. A pixel is
//  - background when !(0 < depth < 1e30): never a source, never filled;
//  - valid (valid[i] != 0, not background): a source; copied to the output bit for bit;
//  - a hole otherwise: filled from valid pixels of the same depth layer, if any.
//
// Depth awareness: every pyramid cell keeps up to 4 depth clusters instead of one average.
// A cluster is a depth interval [lo, hi] covering some of the cell's non-background pixels
// (valid and hole pixels alike: the geometry is known everywhere, only the values are
// missing), with its pixel count n, valid count w and the mean value of its valid pixels.
//  - Pull (fine to coarse, 2x2 children per cell, sizes rounded up so any width and height
//    work): the children's clusters are sorted by lo and merged single-linkage while the next
//    one starts within depth_tolerance * hi of the current one's far end (a continuous
//    surface, even a grazing floor, stays one cluster; a foreground object and the background
//    behind it stay two). If more than 4 remain, the pair with the smallest relative gap is
//    merged until 4 are left.
//  - Push (coarse to fine): a cluster's filled value is alpha * mean + (1 - alpha) * P with
//    alpha = w / n, where P interpolates the 4 nearest parent cells bilinearly (weights
//    9/16, 3/16, 3/16, 1/16), each parent contributing only its filled cluster whose depth
//    interval is nearest to the child's and within depth_tolerance (relative to the nearer
//    depth of the two) of it; parents without one drop out and the weights renormalise. A
//    hole pixel is a cluster [z, z] with alpha = 0, so it takes P.
// So at every level a hole only sees values of its own depth layer: a background hole next to
// a foreground object is filled from the background however coarse the level that finally
// has data, and vice versa. Holes whose layer has no valid pixel anywhere stay unfilled.
//
// Limitation: surfaces whose depth intervals overlap inside a cell (an object standing in
// front of a receding floor at depths the floor also covers there) share one cluster at that
// level, so large holes can mix them.
//
// Deterministic: every cell is computed from its children or parents in a fixed order,
// rows run in parallel, nothing depends on the number of threads.
#pragma once

#include <cstdint>
#include <vector>

namespace hbil {

// value: width*height*channels; valid: 1/0 per pixel; depth: per-pixel view z (see above).
// Returns the filled image: valid pixels unchanged, filled holes with their fill, everything
// else 0 (including background pixels not marked valid; valid background pixels are copied).
// filled (optional): 1 for each hole pixel that received a value, else 0.
// depth_tolerance: relative depth difference still counted as the same surface, e.g. 0.05.
std::vector<float> push_pull(int width, int height, int channels, const std::vector<float>& value,
                             const std::vector<uint8_t>& valid, const std::vector<float>& depth,
                             float depth_tolerance, std::vector<uint8_t>* filled = nullptr);

}  // namespace hbil
