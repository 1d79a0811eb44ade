// Seed 004 (Zheng), §4.6, §5.5 and §6.4: a client walked along a path and measured against the
// sequential reference (docs/vdr.md, "Measuring a client").
#include "cellwalk/systems/vdr/vdr_walk.hpp"

#include <algorithm>
#include <array>
#include <thread>

#include "cellwalk/systems/vdr/traversal.hpp"
#include "core/stopwatch.hpp"

namespace cellwalk::vdr {

struct ReferenceWalk::Impl {
  const VdrModel& model;
  VdrClientOptions options;
  Traversal traversal;
  SelectiveMesh mesh;
  std::vector<Op> ops;

  Impl(const VdrModel& m, const Hello& hello, const VdrClientOptions& o)
      : model(m),
        options(o),
        traversal(m, hello.kind, hello.units),
        mesh(std::span(m.pm.positions).first(m.pm.base_vertex_count), std::span(m.pm.normals).first(m.pm.base_vertex_count),
             m.pm.base_indices) {}
};

ReferenceWalk::ReferenceWalk(const VdrModel& model, const Hello& hello, const VdrClientOptions& options)
    : impl_(std::make_unique<Impl>(model, hello, options)) {}
ReferenceWalk::~ReferenceWalk() = default;

bool ReferenceWalk::prime(const Vec3& eye, const Vec3& aim) {
  for (uint32_t i = 0; i < impl_->options.prime_batches; ++i) {
    step(eye, aim, kPrimeWindow);  // the alarm level of the client's start-up
    if (impl_->ops.empty()) return true;
  }
  return false;
}

const SelectiveMesh& ReferenceWalk::step(const Vec3& eye, const Vec3& aim, uint32_t in_flight) {
  Impl& m = *impl_;
  const int64_t alarm = int64_t(m.options.budget) - 2 * int64_t(m.options.n) * in_flight;
  const BudgetMode mode = int64_t(m.mesh.triangle_count()) > alarm ? BudgetMode::kBudget : BudgetMode::kFree;
  m.ops.clear();
  const uint32_t budget = m.options.server_budget ? m.options.budget : 0;
  m.traversal.manage({eye, aim, m.options.alpha, m.options.tau, mode, m.options.n, budget}, m.ops, kMaxBatchBytes - kBatchHeaderBytes);
  for (const Op& op : m.ops) {
    const WireOp w = wire_op(m.model.pm, op);
    op.split ? m.mesh.vsplit(vsplit_op(w)) : m.mesh.ecol(vsplit_op(w));
  }
  return m.mesh;
}

namespace {
using Triangles = std::vector<std::array<uint32_t, 3>>;

Triangles canonical(Triangles ts) {
  for (auto& t : ts) std::rotate(t.begin(), std::min_element(t.begin(), t.end()), t.end());
  std::sort(ts.begin(), ts.end());
  return ts;
}

double accuracy_of(Triangles mesh, const SelectiveMesh& reference) {
  const auto got = canonical(std::move(mesh)), want = canonical(reference.triangles_by_id());
  if (want.empty()) return 1.0;
  size_t common = 0;
  for (size_t i = 0, j = 0; i < got.size() && j < want.size();) {
    if (got[i] < want[j]) ++i;
    else if (want[j] < got[i]) ++j;
    else ++common, ++i, ++j;
  }
  return double(common) / double(want.size());
}
}  // namespace

double triangle_accuracy(const SelectiveMesh& mesh, const SelectiveMesh& reference) {
  return accuracy_of(mesh.triangles_by_id(), reference);
}

double quantile(std::vector<double> v, double q) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  return v[std::min(v.size() - 1, size_t(q * double(v.size())))];
}

VdrWalkResult walk_vdr(VdrClient& client, const VdrClientOptions& options, const std::vector<VdrFrame>& path,
                       const VdrWalkOptions& walk) {
  VdrWalkResult out;
  // The client's triangles where accuracy is sampled; the reference depends on the path alone,
  // so it runs after the walk and takes no CPU from the client (or, with many, the server).
  std::vector<std::pair<size_t, Triangles>> sampled;
  if (walk.prime && !path.empty()) out.prime = client.prime(path[0].eye, path[0].aim);
  if (walk.after_start_up) walk.after_start_up();
  for (size_t i = 0; i < path.size(); ++i) {
    const Stopwatch frame;
    VdrWalkFrame f;
    f.report = client.frame(path[i].eye, path[i].aim);
    f.render_ms = walk.render ? walk.render(client.mesh(), path[i]) : 0.0;
    const double work = frame.ms();
    if (walk.reference && i % walk.accuracy_every == 0) sampled.emplace_back(i, client.mesh().triangles_by_id());
    const double idle = std::max(0.0, walk.frame_ms - work);
    if (idle > 0) std::this_thread::sleep_for(std::chrono::duration<double, std::milli>(idle));
    f.frame_ms = work + idle;
    client.rendered(f.render_ms + idle);  // a paced client's T_r includes its wait for the display
    out.frames.push_back(f);
  }
  out.stats = client.stats();
  if (walk.before_reference) walk.before_reference();
  double accuracy_sum = 0;
  if (walk.reference) {
    ReferenceWalk reference(*walk.reference, options.hello, options);
    if (walk.prime && !path.empty()) reference.prime(path[0].eye, path[0].aim);
    size_t next = 0;
    for (size_t i = 0; i < path.size() && next < sampled.size(); ++i) {
      const SelectiveMesh& ref = reference.step(path[i].eye, path[i].aim);
      if (sampled[next].first != i) continue;
      out.frames[i].accuracy = accuracy_of(std::move(sampled[next].second), ref);
      accuracy_sum += out.frames[i].accuracy;
      ++next;
    }
  }
  const size_t samples = sampled.size();
  const double n = std::max<double>(1, out.frames.size());
  for (const VdrWalkFrame& f : out.frames) {
    out.mean_frame_ms += f.frame_ms / n;
    out.mean_update_ms += f.report.update_ms / n;
    out.mean_render_ms += f.render_ms / n;
    out.mean_triangles += f.report.triangles / n;
    out.mean_ops += f.report.ops / n;
    out.unmodified_share += (f.report.modified ? 0.0 : 1.0) / n;
  }
  if (samples > 0) out.mean_accuracy = accuracy_sum / samples;
  // T_g of the walk's batches: start-up's come first and are left out.
  const std::vector<double> walked(out.stats.batch_ms.begin() + std::min<size_t>(out.prime.batches, out.stats.batch_ms.size()),
                                   out.stats.batch_ms.end());
  out.batch_p50_ms = quantile(walked, 0.50);
  out.batch_p99_ms = quantile(walked, 0.99);
  return out;
}

}  // namespace cellwalk::vdr
