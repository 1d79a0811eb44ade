// The DoV engine's cube-map modes against each other on the same cells (HDoV thesis §5.5.2,
// digest 000 §3.9): speed, and the largest difference of region DoVs.
#include "precompute/dov_compare.hpp"

#include <algorithm>
#include <cmath>
#include <memory>

#include <tbb/parallel_for.h>

#include "core/stopwatch.hpp"
#include "precompute/dov_engine.hpp"
#include "precompute/sampling_engine.hpp"

namespace cellwalk::visibility {

namespace {

double timed(const std::function<void()>& work) {
  Stopwatch watch;
  work();
  return watch.ms() / 1000.0;
}

// Adds one cell's two sets (ascending ids) to the differences.
void add_differences(const VisibleSet& exact, const VisibleSet& mode, DovComparison& out) {
  size_t i = 0, j = 0;
  while (i < exact.objects.size() || j < mode.objects.size()) {
    const bool in_exact = i < exact.objects.size() && (j == mode.objects.size() || exact.objects[i] <= mode.objects[j]);
    const bool in_mode = j < mode.objects.size() && (i == exact.objects.size() || mode.objects[j] <= exact.objects[i]);
    const double a = in_exact ? exact.dov[i++] : 0.0, b = in_mode ? mode.dov[j++] : 0.0;
    ++out.pairs;
    out.max_difference = std::max(out.max_difference, std::abs(a - b));
    if (in_exact != in_mode) {
      ++out.one_sided;
      out.one_sided_max_dov = std::max(out.one_sided_max_dov, a + b);
    }
  }
}

}  // namespace

DovComparison compare_dov_cubes(const World& world, const EngineOptions& options, const ViewCellPartition& partition,
                                std::span<const CellId> cells, const std::function<void(uint64_t, uint64_t)>& progress) {
  EngineOptions exact_options = options;
  exact_options.dov_cubes = DovCubes::kExact;
  const auto scene = std::make_shared<const EmbreeScene>(world);
  const SamplingEngine step1(world, options, scene);
  // No prior: step 1 is timed on its own, and the DoVs compared are those of pixels.
  const DovEngine exact(world, exact_options, nullptr, scene);
  const DovEngine mode(world, options, nullptr, scene);
  DovComparison out;
  out.mode = options.dov_cubes;
  out.resolution = options.dov_resolution;
  const std::vector<double> weights = cube_pixel_weights(options.dov_resolution, options.dov_midpoint_weights);
  out.largest_pixel_weight = *std::max_element(weights.begin(), weights.end());
  if (cells.empty()) return out;
  exact.compute(partition.cell(cells[0]));  // GL decodes and uploads every mesh once
  for (size_t k = 0; k < cells.size(); ++k) {
    const ViewCell& cell = partition.cell(cells[k]);
    VisibleSet a, b;
    const auto run_exact = [&] { out.exact_seconds += timed([&] { a = exact.compute(cell); }); };
    const auto run_mode = [&] { out.mode_seconds += timed([&] { b = mode.compute(cell); }); };
    if (k % 2 == 0) {
      run_exact();
      run_mode();
    } else {
      run_mode();
      run_exact();
    }
    add_differences(a, b, out);
    ++out.cells;
    if (progress) progress(out.cells, cells.size());
  }
  // Step 1 casts one cell's rays on one core; a pvs run computes cells in parallel, so it is
  // timed the same way: all the cells at once.
  out.step1_seconds = timed([&] {
    tbb::parallel_for(size_t(0), cells.size(), size_t(1), [&](size_t k) { step1.compute(partition.cell(cells[k])); });
  });
  return out;
}

}  // namespace cellwalk::visibility
