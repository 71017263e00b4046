#pragma once
// A layer's whole-map PNG overview (GET /api/maps/{id}/layers/LAYER.png?max=N) drawn from a
// stored map's pyramid (maps/dem_pyramid.hpp) instead of the map in memory: the level of blocks
// just larger than the overview (under twice its side, so under four times its cells, and never
// more than kMaxOverviewLevelCells) is read, the layer computed on it the way its tiles are (slope
// and hillshade of the block means, the worst class of a block, the mean mass), and
// box-downsampled to the overview's size by renderLayer with its legend. A 1024-px overview of a
// 20000 × 15000 map reads its 1250 × 938 level (1.2 M cells; at most 4 M for any map), never the map.
#include "maps/map_tiles.hpp"
#include "maps/render.hpp"

namespace rover::maps {

// The cells per block of the level an overview of longest side `side` (> 0) of a rows × cols map
// is drawn from: the largest power of two whose blocks still number at least `side` along the
// longer side (1 when the map is no larger than the overview), doubled while the level holds
// more than kMaxOverviewLevelCells cells (the largest overview's, 4096²).
inline constexpr long long kMaxOverviewLevelCells = 4096LL * 4096;
int overviewStep(int rows, int cols, int side);

// The overview of `layer` of a rows × cols map whose blocks `source` answers; the ramp of
// elevation and pdm spans the drawn grid (as renderLayer's overviews do).
Image renderOverview(RenderLayer layer, const TileBlocks& source, int rows, int cols, int side);

}  // namespace rover::maps
