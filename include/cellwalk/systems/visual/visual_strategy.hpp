// VISUAL (HDoV thesis ch. 5, §5.3 and §5.8.5; digest 000 §2.2): the walkthrough system over the
// disk HDoV-tree (cellwalk/systems/visual/hdov_tree.hpp): building the tree from a world's
// stored DoVs, and the strategy "visual". Choices where the thesis is silent: docs/visual.md.
#pragma once

#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "cellwalk/strategy/strategy.hpp"
#include "cellwalk/systems/visual/hdov_tree.hpp"

namespace cellwalk {

// Builds the HDoV-tree of a world from its stored DoVs (the "cells" and "dov" sections that
// `cellwalk pvs WORLD --engine dov --cells grid:SIZE` writes) and writes it to `path`. Throws
// Error naming the world and the command if it has no DoVs.
HdovTreeBuild build_visual_tree(const World& world, const std::string& path, const HdovBuildParams& params,
                                const std::function<void(uint64_t, uint64_t)>& progress = {});

// Strategy "visual" (thesis §5.3, §5.8.5): on entering a view cell, flip to its V-page index
// segment and run the threshold search; draw its picks; models already buffered are not read
// again (the delta search). Name: "visual[:key=value,...]" with keys
//   eta=0.001      η (default: StrategyOptions::eta)
//   scheme=iv      h | v | iv
//   cache=64       node cache, pages
//   policy=dt      none | lru | dov | dt (T in searches) | dt-access (T in page requests)
//   maxdov=0.5     MAXDOV of eq. 5.6
//   tree=PATH      the HDoV-tree file (default WORLD.hdov, built from the world's DoVs if missing)
struct VisualConfig {
  std::optional<double> eta;
  VPageScheme scheme = VPageScheme::kIndexedVertical;
  HdovCacheOptions cache;
  double max_dov = 0.5;
  std::string tree_file;
};
bool is_visual_strategy_name(const std::string& name);
VisualConfig parse_visual_strategy_name(const std::string& name);

// One query (a cell change).
struct VisualQuery {
  uint64_t frame = 0;
  CellId cell = 0;
  HdovCounters io;
  uint64_t picks = 0, new_models = 0;  // new: not buffered when the query ran (delta search)
  double search_ms = 0;
};

class VisualStrategy : public Strategy {
 public:
  // Throws Error if the budget cannot hold the tree's directory, node cache and segment.
  VisualStrategy(const World& world, const VisualConfig& config, const StrategyOptions& options);
  ~VisualStrategy() override;
  std::string name() const override;
  void select(const Camera& camera, std::vector<DrawItem>& items, FrameStats& stats) override;
  bool serves_every_level() const override { return true; }
  const Mesh* mesh(const DrawItem& item, FrameStats& stats) override;
  uint64_t resident_bytes() const override;
  uint64_t peak_resident_bytes() const override;
  QueryTotals query_totals() const override;  // disk I/Os: light I/Os (HdovCounters)
  const std::vector<VisualQuery>& queries() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace cellwalk
