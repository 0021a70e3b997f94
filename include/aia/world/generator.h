// Structured worlds (workspace.obstacles.generator; docs/scenarios.md,
// "Generated worlds"): mazes, offices of rooms with doors, corridors lined
// with rooms, caves. Each is laid out on the robots.step lattice, so that
// which lattice points are free and which moves are valid follows from the
// layout alone:
//   - widths are whole lattice cells (the step x step squares around the
//     points);
//   - a thin wall (thinner than step - 2 radius) stands on a line between
//     two rows or columns of points: every point stays free, and a move
//     across the wall is blocked while a move through a gap (a door, an
//     opened maze wall) is valid whatever the walls around it;
//   - cave rock fills whole lattice cells, whose points are blocked, while
//     a free cell's point keeps step / 2 > radius from the rock.
// Connected free space is then a property of the layout's graph: a spanning
// tree of maze cells, one door per split of the rooms, rooms opening onto
// connected corridors, the largest connected part of a cave (the rest is
// filled). The layout is rasterized (thin walls as narrow pixel columns)
// and merged into boxes by BoxesFromImage, as map images are.
#ifndef AIA_WORLD_GENERATOR_H_
#define AIA_WORLD_GENERATOR_H_

#include <vector>

#include "aia/core/geometry.h"
#include "aia/scenario/config.h"
#include "aia/world/lattice.h"

namespace aia {

struct GeneratedObstacles {
  std::vector<Box> boxes;
  // Lattice points the layout leaves free (all of them but those in cave
  // rock): the world's lattice must have exactly these, connected.
  int free_points = 0;
};

// The boxes of the scenario's generator, drawn from the stream
// `obstacles.generator` of the scenario seed (the same seed gives the same
// boxes, bit for bit). Linear in the lattice points. Throws InputError at
// workspace.obstacles.generator when the boxes would pass the body limit
// with the scenario's robots and targets (the count stops early), or when a
// cave has no free space. The scenario has been validated.
GeneratedObstacles GenerateObstacles(const Scenario& scenario);

// Checks, by the lattice's own flood fill, that the generated world leaves
// every free point of its layout free and all of them connected; throws
// InputError at workspace.obstacles.generator when not (a broken layout).
void CheckGeneratedLattice(const Scenario& scenario,
                           const GeneratedObstacles& generated,
                           const Lattice& lattice);

}  // namespace aia

#endif  // AIA_WORLD_GENERATOR_H_
