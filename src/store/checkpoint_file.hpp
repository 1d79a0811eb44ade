// Checkpoint and part files of the resumable precomputations (`pvs`, `stratify build`): a header
// each command writes and reads itself, then framed records — u32 payload length, u64 XXH3-64 of
// the payload, the payload — appended one write() each, so a killed or crashed run tears at most
// the last record, and a resumed run redoes only what follows the last intact one.
#pragma once

#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "core/bytes.hpp"

namespace cellwalk {

// `payload` framed, appended to `out`.
void append_framed_record(std::vector<uint8_t>& out, std::span<const uint8_t> payload);

// The payload of the intact record at `r`, advancing past it; nullopt at the end or at a torn or
// damaged record (`r` is then left where that record starts).
std::optional<std::vector<uint8_t>> next_framed_record(ByteReader& r);

// The whole file; throws Error naming it when it cannot be read.
std::vector<uint8_t> read_checkpoint_file(const std::string& path);

// Appends to a checkpoint, one write() a call. Not thread-safe: one writer a file.
class CheckpointWriter {
 public:
  // Keeps the first `keep_bytes` of `path` (its intact part) and appends after them; with
  // keep_bytes = 0 the file starts over with `header`. Throws Error naming the file.
  CheckpointWriter(const std::string& path, uint64_t keep_bytes, std::span<const uint8_t> header);
  ~CheckpointWriter();  // flushes to disk
  CheckpointWriter(const CheckpointWriter&) = delete;
  CheckpointWriter& operator=(const CheckpointWriter&) = delete;
  // Throws Error naming the file; a full disk says that a rerun resumes from the checkpoint.
  void write_all(std::span<const uint8_t> bytes);

 private:
  std::string path_;
  int fd_ = -1;
};

}  // namespace cellwalk
