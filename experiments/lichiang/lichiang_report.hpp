// `cellwalk bench lichiang` (issue 18): Li & Chiang's experiment (seed 003, "Experimental
// Results") measured on our code: the seed's four cases — no cache or prefetch; LRU only; LRU
// with one-step prefetching; the hybrid cache with relevance-matrix prefetching — walked along
// each path kind of each world, under budgets whose cache share is a fraction of the world's
// geometry (so the world does not fit), with the GPU cache held small so the store is what
// caches. Per case: mean and standard deviation of frame time, the hit ratio of the store's
// requests, stall frames (a frame that read geometry it had to draw), bytes read, and the
// process's strategy peak against its budget. Each case walks on its own, with a fresh strategy
// and renderer (interleaving would hand one case's prefetch thread the others' frames).
// Then the same four cases on each world's first path at each cache share over slower storage
// (the page cache bypassed; bypassed with a per-read latency), and the seed's future work: the
// effect of cache size against allowable prefetching time (case 4 with t_p on the frame's
// thread, tp_ms, over a grid of cache shares and t_p) on the largest world's first path, on the
// slow disk.
// Writes <out>/lichiang.md, <out>/lichiang/cases.csv, storage.csv, tp.csv and tp-*.svg.
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
  // Storage the cases also run on (each world's first path; the main table reads the world
  // file through the OS page cache): "direct" (the page cache bypassed), "slow" (bypassed, and
  // read_latency_ms before every read), "sqlite" (the object database of `cellwalk db`, one
  // query per object as the seed's DBMS; the cases' budgets grown by the database's bound so
  // the cache share is the same).
  std::vector<std::string> storages = {"direct", "slow", "sqlite"};
  double read_latency_ms = 2.0;
  // The cache size against prefetch time plot (the seed's future work): case 4 with tp_ms = each
  // of plot_tp_ms at each of plot_fractions. Empty: no plot.
  std::vector<double> plot_fractions = {0.02, 0.05, 0.1, 0.25, 0.5};
  std::vector<double> plot_tp_ms = {0, 2, 5, 10, 20, 40};
  double gpu_mib = 1.0;            // the renderer's buffer cache
  int width = 256, height = 192;
  int threads = 0;                 // precompute threads, 0 = all cores
  std::string out_dir = "docs/results";
  std::string work_dir;            // empty = a temporary directory, removed at the end
  std::string command_line;
};

// The seed's cases, in its order, as strategy names.
const std::vector<std::string>& lichiang_cases();

nlohmann::ordered_json run_lichiang_bench(const LiChiangBenchParams& params);

}  // namespace cellwalk
