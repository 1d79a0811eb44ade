// ReplacementPolicy: which cached entry the BufferManager evicts next.
// Sources (seeds/digests/000_hdov_thesis.md unless noted):
//   LRU                   the baseline of §3.4 and §3.11.
//   DistancePriorityLRU   §3.4 (thesis §4.2.4): level priority, block distance, age QN.
//   DoV, DoV-Time         §3.11 (thesis §5.7): lowest DoV; DoV + κ·T with κ = 0.001.
//   HybridRelevance       seeds/003 (Li & Chiang 1999), "Data Caching: Hybrid Cache Model".
//
// Thread-safety: none; the owner (BufferManager) serialises calls.
// Every operation is O(1) (LRU) or O(log n) (the scored policies), except
// DistancePriorityLRU::on_query, which re-scores every entry once per query (O(n log n)).
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <optional>
#include <set>
#include <unordered_map>

namespace cellwalk {

using CacheKey = uint64_t;

// An axis-aligned box in world units; DistancePriorityLRU measures block distance between boxes.
struct BlockBox {
  std::array<float, 3> lo{0, 0, 0};
  std::array<float, 3> hi{0, 0, 0};
};

// The thesis's block distance DIST(A, B) (§3.4): 0 if the boxes overlap, else the largest of the
// per-axis gaps (a Chebyshev-style distance).
float block_distance(const BlockBox& a, const BlockBox& b);

// What the policies need to know about an entry. Each policy reads only its own fields; the
// caller fills the ones of the policy in use and passes fresh values on every access.
struct EntryMeta {
  uint32_t level = 0;      // tree level, root = 0, deeper = larger (DPLRU's level priority P)
  BlockBox box;            // the entry's bounding box (DPLRU's BB)
  float dov = 0.0f;        // degree of visibility in the current view cell (DoV, DoV-Time)
  float relevance = 0.0f;  // Li-Chiang relevance of the object for the current viewpoint
  uint64_t frame = 0;      // frame of the request (HybridRelevance)
};

// What a new query (a frame, or a cell change) tells the policies.
struct QueryContext {
  BlockBox cell;       // the current query cell Q (DPLRU)
  uint64_t frame = 0;  // the current frame number
};

class ReplacementPolicy {
 public:
  virtual ~ReplacementPolicy() = default;

  // REQUIRES: key is not tracked yet.
  virtual void on_insert(CacheKey key, const EntryMeta& meta) = 0;
  // A hit. REQUIRES: key is tracked. `meta` replaces the stored meta.
  virtual void on_access(CacheKey key, const EntryMeta& meta) = 0;
  // Forgets key. REQUIRES: key is tracked (pinned or not).
  virtual void on_erase(CacheKey key) = 0;
  // The entry to evict next, never a pinned one; nullopt when every entry is pinned or none exist.
  virtual std::optional<CacheKey> victim() const = 0;
  // Pins nest: an entry is evictable again after as many unpin() as pin() calls. The last
  // unpin() counts as an access with the stored meta: the entry was in use until then.
  // REQUIRES: key is tracked; unpin only after pin.
  virtual void pin(CacheKey key) = 0;
  virtual void unpin(CacheKey key) = 0;
  // A new query or frame begins (DPLRU ages its entries and re-scores; others ignore it).
  virtual void on_query(const QueryContext&) {}
  // Whether a prefetch admitted now with `newcomer` may evict `key` (the victim() of the
  // moment) to make room: a guess about the future must not displace what the policy keeps
  // longer. REQUIRES: key is tracked. Every policy but HybridRelevance: yes.
  virtual bool yields_to_prefetch(CacheKey key, const EntryMeta& newcomer) const {
    (void)key, (void)newcomer;
    return true;
  }
  virtual size_t size() const = 0;
};

// Least recently used: a list in access order plus a hash map into it. O(1).
std::unique_ptr<ReplacementPolicy> make_lru_policy();

// Weights of DPLRU's score f = α·pp + β·pd + γ·pl (§3.4; the thesis tuned α = β = γ = 1/3).
struct DistancePriorityWeights {
  double alpha = 1.0 / 3.0;  // level priority P
  double beta = 1.0 / 3.0;   // block distance to the query cell
  double gamma = 1.0 / 3.0;  // age QN (queries since the last access)
};
std::unique_ptr<ReplacementPolicy> make_distance_priority_lru_policy(
    DistancePriorityWeights weights = {});

// Evicts the lowest DoV (§3.11 "DoV policy").
std::unique_ptr<ReplacementPolicy> make_dov_policy();
// What DoV-Time's T counts (§3.11 leaves the time unit open): requests to the cache, or
// queries (on_query() calls; the thesis's node cache ages once per HDoV-tree search).
enum class DovTimeClock { kAccesses, kQueries };
// Evicts the lowest DoV + κ·T, T = the entry's last access time on `clock` (§3.11 "DoV-Time");
// ties go to the least recently accessed entry.
std::unique_ptr<ReplacementPolicy> make_dov_time_policy(double kappa = 0.001,
                                                        DovTimeClock clock = DovTimeClock::kAccesses);
// LRU across frames, lowest relevance first within the least recently used frame (seeds/003).
// A prefetch evicts only entries that order puts before it: of an older frame, or of its own
// frame and less relevant.
std::unique_ptr<ReplacementPolicy> make_hybrid_relevance_policy();

// The mechanism of every policy but LRU: an ordered set of (score, key) plus a hash map from key
// to entry; the victim is the unpinned entry with the smallest score (ties: smaller key).
// Subclasses define the score; pinned entries are kept out of the ordered set.
class ScoredPolicy : public ReplacementPolicy {
 public:
  // Compared lexicographically; smaller is evicted first.
  using Score = std::array<double, 3>;

  void on_insert(CacheKey key, const EntryMeta& meta) override;
  void on_access(CacheKey key, const EntryMeta& meta) override;
  void on_erase(CacheKey key) override;
  std::optional<CacheKey> victim() const override;
  void pin(CacheKey key) override;
  void unpin(CacheKey key) override;
  size_t size() const override { return entries_.size(); }

 protected:
  struct Entry {
    EntryMeta meta;
    uint64_t last_access = 0;  // value of the access clock at the last insert/access (from 1)
    uint64_t last_query = 0;   // value of the query clock at the last insert/access
    uint32_t pins = 0;
    Score score{};
  };
  virtual Score score(const Entry& entry) const = 0;

  // Advances the query clock (entries' last_query is taken from it).
  void advance_query_clock() { ++query_clock_; }
  uint64_t query_clock() const { return query_clock_; }
  // Recomputes every entry's score, e.g. after the inputs of score() changed for all entries.
  void rescore_all();
  const std::unordered_map<CacheKey, Entry>& entries() const { return entries_; }

 private:
  Entry& find(CacheKey key);
  void touch(Entry& entry, const EntryMeta& meta);
  void order_insert(CacheKey key, Entry& entry);
  void order_erase(CacheKey key, const Entry& entry);

  std::unordered_map<CacheKey, Entry> entries_;
  std::set<std::pair<Score, CacheKey>> order_;  // unpinned entries only
  uint64_t access_clock_ = 0;
  uint64_t query_clock_ = 0;
};

}  // namespace cellwalk
