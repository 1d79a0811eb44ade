// `cellwalk bench lichiang` (issue 18): Li & Chiang's experiment (seed 003, "Experimental
// Results") measured on our code: the seed's four cases — no cache or prefetch; LRU only; LRU
// with one-step prefetching; the hybrid cache with relevance-matrix prefetching — walked along
// each path kind of each world, under budgets whose cache share is a fraction of the world's
// geometry (so the world does not fit), with the GPU cache held small so the store is what
// caches. Per case: mean and standard deviation of frame time, the hit ratio of the store's
// requests, stall frames (a frame that read geometry it had to draw), bytes read, and the
// process's strategy peak against its budget. Each case walks on its own, with a fresh strategy
// and renderer (interleaving would hand one case's prefetch thread the others' frames).
// Writes <out>/lichiang.md and <out>/lichiang/cases.csv.
#pragma once

#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "cellwalk/scene/generators.hpp"

namespace cellwalk {

struct LiChiangBenchParams {
  // The seed's two worlds had 128 and 370 objects; the third is a city of our own.
  std::vector<uint64_t> world_objects = {128, 370, 6000};
  double landmark_fraction = 0.0;  // the seed's objects were alike: no landmark models
  uint64_t city_seed = 11;
  float cell_size = 20.0f;         // view cells (grid, metres)
  float along_margin = 40.0f;      // sets are computed for the cells within this of a path
  std::vector<std::string> path_kinds = {"normal", "slow", "fast", "turning", "backward", "back-and-forth", "random"};
  int frames = 240;
  uint64_t path_seed = 5;
  // The store's cache shares, as fractions of the world's geometry: every case runs at each.
  std::vector<double> cache_fractions = {0.05, 0.5};
  double gpu_mib = 1.0;            // the renderer's buffer cache
  int width = 256, height = 192;
  int threads = 0;                 // precompute threads, 0 = all cores
  // Where the store reads objects: "file" (the world file's pages) and "sqlite" (the object
  // database, `cellwalk db`, one query per object as the seed's DBMS). sqlite runs on the first
  // world only, the cases' budgets grown by the database's bound so the cache share is the same.
  std::vector<std::string> backends = {"file", "sqlite"};
  std::string out_dir = "docs/results";
  std::string work_dir;            // empty = a temporary directory, removed at the end
  std::string command_line;
};

// The seed's cases, in its order, as strategy names.
const std::vector<std::string>& lichiang_cases();

nlohmann::ordered_json run_lichiang_bench(const LiChiangBenchParams& params);

}  // namespace cellwalk
