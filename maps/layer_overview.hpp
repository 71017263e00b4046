#pragma once
// A layer's whole-map PNG overview (GET /api/maps/{id}/layers/LAYER.png?max=N) drawn from a
// stored map's pyramid (maps/dem_pyramid.hpp) instead of the map in memory: the level of blocks
// just larger than the overview (at most twice its cells) is read, the layer computed on it the way
// its tiles are (slope and hillshade of the block means, the worst class of a block, the mean
// mass), and box-downsampled to the overview's size by renderLayer with its legend. A 1024-px
// overview of a 300 M-cell map reads about 4 M cells, never the map.
#include "maps/map_tiles.hpp"
#include "maps/render.hpp"

namespace rover::maps {

// The cells per block of the level an overview of longest side `side` (> 0) of a rows × cols map
// is drawn from: the largest power of two whose blocks still number at least `side` along the
// longer side (1 when the map is no larger than the overview).
int overviewStep(int rows, int cols, int side);

// The overview of `layer` of a rows × cols map whose blocks `source` answers; the ramp of
// elevation and pdm spans the drawn grid (as renderLayer's overviews do).
Image renderOverview(RenderLayer layer, const TileBlocks& source, int rows, int cols, int side);

}  // namespace rover::maps
