// Checks every command shares on what a user gives it (docs/testing.md "Hostile input"): option
// values are finite and inside bounds a person can read, counts are bounded, an output is never
// one of the inputs, and a path names the world it was made for.
#pragma once

#include <CLI/CLI.hpp>

#include <cstdint>
#include <string>
#include <vector>

#include "cellwalk/core/camera_path.hpp"
#include "cellwalk/scene/scene.hpp"

namespace cellwalk::app {

// The most worker threads any command starts (0 means one per core).
constexpr int64_t kMaxThreads = 256;
// The most objects a generator writes; larger worlds are estimated and refused up front.
constexpr uint64_t kMaxObjects = 10'000'000;

// A finite number in [lo, hi], or in (lo, hi] with `open_low` (NaN and infinities fail).
CLI::Validator number_in(double lo, double hi, bool open_low = false);
// A whole number in [lo, hi], read as written (a minus sign is not wrapped to a huge unsigned).
CLI::Validator integer_in(int64_t lo, int64_t hi);
// --threads: 0 (all cores) to kMaxThreads.
CLI::Validator thread_count();
// --page-size: a power of two from 512 bytes to 1 MiB, what a world file allows.
CLI::Validator page_size_check();
// A path kind parse_session_kind knows (normal, slow, fast, ...).
CLI::Validator session_kind_check();

// Fails, naming both paths, when an output is one of the inputs (also through symlinks, hard
// links and "./" spellings) or two outputs are the same file: writing would destroy the input.
void refuse_same_files(const std::vector<std::string>& inputs, const std::vector<std::string>& outputs);

// An output folder made for a run: created (with any missing parents) at construction; the
// folders it created are removed again at destruction while still empty, so a run that fails
// before writing (a full disk, a bad strategy) leaves nothing behind.
class OutputFolder {
 public:
  explicit OutputFolder(const std::string& folder);
  ~OutputFolder();
  OutputFolder(OutputFolder&& other) noexcept : created_(std::move(other.created_)) { other.created_.clear(); }
  OutputFolder(const OutputFolder&) = delete;
  OutputFolder& operator=(const OutputFolder&) = delete;

 private:
  void remove_empty();
  std::vector<std::string> created_;  // deepest first
};

// What a path file records of the world it was made for (docs/paths.md): the scene's generator
// and a hash of its navigation graph, which is all a generated path depends on.
PathWorld path_world(const SceneInfo& info);
// Warns on stderr when `path` (read from `path_file`) was made for another world than `info`.
void warn_if_other_world(const CameraPath& path, const std::string& path_file, const SceneInfo& info,
                         const std::string& world_file);

}  // namespace cellwalk::app
