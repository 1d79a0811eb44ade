#include "store/checkpoint_file.hpp"

#include <fcntl.h>
#include <unistd.h>
#include <xxhash.h>

#include <cerrno>
#include <cstring>
#include <fstream>
#include <iterator>

#include "cellwalk/core/error.hpp"

namespace cellwalk {

void append_framed_record(std::vector<uint8_t>& out, std::span<const uint8_t> payload) {
  ByteWriter w;
  w.put(uint32_t(payload.size()));
  w.put(XXH3_64bits(payload.data(), payload.size()));
  out.insert(out.end(), w.bytes().begin(), w.bytes().end());
  out.insert(out.end(), payload.begin(), payload.end());
}

std::optional<std::vector<uint8_t>> next_framed_record(ByteReader& r) {
  if (r.remaining() < 12) return std::nullopt;
  ByteReader peek = r;
  const uint32_t len = peek.get<uint32_t>("record length");
  const uint64_t sum = peek.get<uint64_t>("record checksum");
  if (len > peek.remaining()) return std::nullopt;
  std::vector<uint8_t> payload = peek.get_array<uint8_t>(len, "record");
  if (XXH3_64bits(payload.data(), payload.size()) != sum) return std::nullopt;
  r = peek;
  return payload;
}

std::vector<uint8_t> read_checkpoint_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) fail(path, std::string("cannot open: ") + std::strerror(errno));
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

CheckpointWriter::CheckpointWriter(const std::string& path, uint64_t keep_bytes, std::span<const uint8_t> header)
    : path_(path) {
  fd_ = ::open(path.c_str(), O_WRONLY | O_CREAT, 0644);
  if (fd_ < 0) fail(path, std::string("cannot open for writing: ") + std::strerror(errno));
  if (::ftruncate(fd_, off_t(keep_bytes)) != 0) {
    const int err = errno;
    ::close(fd_);
    fail(path, std::string("cannot truncate: ") + std::strerror(err));
  }
  ::lseek(fd_, off_t(keep_bytes), SEEK_SET);
  if (keep_bytes == 0) write_all(header);
}

CheckpointWriter::~CheckpointWriter() {
  ::fdatasync(fd_);
  ::close(fd_);
}

void CheckpointWriter::write_all(std::span<const uint8_t> bytes) {
  size_t done = 0;
  while (done < bytes.size()) {
    const ssize_t n = ::write(fd_, bytes.data() + done, bytes.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      const int err = n < 0 ? errno : ENOSPC;
      fail(path_, std::string("write failed: ") + std::strerror(err) +
                      (err == ENOSPC ? " (free some space and run again: the run resumes from this checkpoint)" : ""));
    }
    done += size_t(n);
  }
}

}  // namespace cellwalk
