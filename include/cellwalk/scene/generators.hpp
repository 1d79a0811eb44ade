// Deterministic world generators. Each streams its objects into a sink (never the whole world
// in memory) and returns the SceneInfo, including the navigation graph paths walk on.
// Same parameters and seed: the same world, bit for bit, on any machine.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "cellwalk/scene/scene.hpp"

namespace cellwalk {

// A grid cityscape after the HDoV thesis §3.3: streets 10–30 m wide, lots 10–30 m apart, buildings
// of several designs (houses and towers of a few hundred to ~1,800 triangles) and high-detail
// landmark objects (a ~70k-triangle bunny) repeated with random transforms.
struct CityParams {
  uint64_t objects = 2000;
  double landmark_fraction = 0.01;
  double extent = 0.0;  // side of the square city in metres; 0 = derived from the object count
  uint64_t seed = 1;
  std::string landmark_mesh;  // OFF/PLY/OBJ/glTF file; empty = the CGAL bunny under data/
};
SceneInfo generate_city(const CityParams& params, ObjectSink& sink);

// The random city of the stratified-rendering thesis, Appendix A.
struct StratifiedCityParams {
  double max_height = 60.0;
  double block_length = 80.0, block_width = 60.0;
  int rows_per_block = 3, columns_per_block = 4;
  int blocks_x = 8, blocks_z = 8;
  double street_width = 16.0, street_height = 0.1;
  double curb_width = 2.0, curb_height = 0.15;
  double tree_spacing = 8.0;
  uint64_t seed = 1;
};
SceneInfo generate_stratified_city(const StratifiedCityParams& params, ObjectSink& sink);

// An industrial plant standing in for the UNC Power Plant: pipes, tanks, boilers, walkways,
// ladders, many small parts, long sight lines along its aisles.
struct PlantParams {
  int units_x = 8, units_z = 8;  // process units on a grid separated by aisles
  double detail = 2.0;           // scales tessellation and part counts
  uint64_t seed = 1;
};
SceneInfo generate_plant(const PlantParams& params, ObjectSink& sink);

// Instances of one imported mesh on an nx × ny × nz lattice, with walkable lanes between.
struct GridParams {
  std::string mesh;
  int nx = 10, ny = 1, nz = 10;
  // The mesh is first scaled so its largest extent is 1; spacing is in those units (0 = 1.5).
  double spacing = 0.0;
  uint64_t seed = 1;     // for per-instance colours
};
SceneInfo generate_grid(const GridParams& params, ObjectSink& sink);

// An indoor level as game editors write one (issue 15): rooms on a grid (10 m slots, 4–8 m
// rooms, 3–4 m high) joined by straight corridors (a spanning tree and some loops), carved out
// of solid. Every floor, wall and ceiling is a single-sided face facing into the open space,
// one object each, tiled into quads of at most `tile` metres: closed only all together.
// `crates` closed boxes stand on each room's floor. The navigation graph runs from room
// centres through every corridor at eye height.
struct LevelParams {
  int rooms_x = 5, rooms_z = 5;
  double tile = 0.5;  // metres; 0: one quad per face
  int crates = 3;
  uint64_t seed = 1;
};
SceneInfo generate_level(const LevelParams& params, ObjectSink& sink);

// One face of a carved level: a rectangle tiled into quads, and its normal.
struct CarvedFace {
  Mesh mesh;
  Vec3 normal;
};
// The boundary of a union of axis-aligned open boxes as single-sided rectangles facing into
// the open space: coplanar neighbours merged greedily into maximal rectangles, each tiled
// into quads of at most `tile` metres (0: one quad).
std::vector<CarvedFace> carved_faces(const std::vector<Aabb>& spaces, double tile);

// Where the project keeps the meshes scripts/setup unpacks (data/cgal/meshes/...).
std::string data_path(const std::string& relative);

// The browser client's folder (web/, its npm packages installed by scripts/setup):
// $CELLWALK_WEB when set, else the source tree's web/ this library was built from.
std::string web_client_dir();

}  // namespace cellwalk
