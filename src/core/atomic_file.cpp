#include "cellwalk/core/atomic_file.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <filesystem>

#include "cellwalk/core/error.hpp"

namespace cellwalk {
namespace {

constexpr size_t kBufferBytes = 1 << 20;

void sync_directory_of(const std::string& path) {
  std::filesystem::path dir = std::filesystem::path(path).parent_path();
  if (dir.empty()) dir = ".";
  int fd = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY);
  if (fd >= 0) {
    ::fsync(fd);  // best effort: some file systems refuse fsync on directories
    ::close(fd);
  }
}

}  // namespace

AtomicFile::AtomicFile(std::string path) : path_(std::move(path)) {
  if (std::filesystem::is_directory(path_)) fail(path_, "is a directory, expected a file name");
  temp_ = path_ + ".tmp." + std::to_string(::getpid());
  // Read and write: append_contents_of() reads a scratch file back.
  fd_ = ::open(temp_.c_str(), O_RDWR | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd_ < 0) fail(path_, std::string("cannot create: ") + std::strerror(errno));
  buffer_.reserve(kBufferBytes);
}

AtomicFile::~AtomicFile() {
  if (fd_ >= 0) {
    ::close(fd_);
    ::unlink(temp_.c_str());
  }
}

void AtomicFile::write(std::span<const uint8_t> bytes) {
  written_ += bytes.size();
  if (buffer_.size() + bytes.size() > kBufferBytes) flush();
  if (bytes.size() >= kBufferBytes) {
    buffer_.assign(reinterpret_cast<const char*>(bytes.data()), bytes.size());
    flush();
    return;
  }
  buffer_.append(reinterpret_cast<const char*>(bytes.data()), bytes.size());
}

void AtomicFile::overwrite(uint64_t offset, std::span<const uint8_t> bytes) {
  if (offset + bytes.size() > written_) fail(path_, "internal: overwrite past the end of the file");
  flush();
  size_t done = 0;
  while (done < bytes.size()) {
    ssize_t n = ::pwrite(fd_, bytes.data() + done, bytes.size() - done, static_cast<off_t>(offset + done));
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) fail(path_, std::string("write failed: ") + std::strerror(n < 0 ? errno : EIO));
    done += static_cast<size_t>(n);
  }
}

void AtomicFile::append_contents_of(AtomicFile& other) {
  other.flush();
  std::string chunk(kBufferBytes, '\0');
  for (uint64_t offset = 0; offset < other.written_;) {
    const uint64_t left = other.written_ - offset;
    const auto want = static_cast<size_t>(std::min<uint64_t>(chunk.size(), left));
    ssize_t n = ::pread(other.fd_, chunk.data(), want, static_cast<off_t>(offset));
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0)
      fail(other.path_, std::string("read back failed: ") + std::strerror(n < 0 ? errno : EIO));
    write(std::string_view(chunk.data(), static_cast<size_t>(n)));
    offset += static_cast<uint64_t>(n);
  }
}

void AtomicFile::flush() {
  size_t done = 0;
  while (done < buffer_.size()) {
    ssize_t n = ::write(fd_, buffer_.data() + done, buffer_.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      int err = n < 0 ? errno : ENOSPC;
      fail(path_, std::string("write failed: ") + std::strerror(err) +
                      (err == ENOSPC ? " (free some space and run again; the previous file is intact)"
                                     : ""));
    }
    done += static_cast<size_t>(n);
  }
  buffer_.clear();
}

void AtomicFile::commit() {
  flush();
  if (::fsync(fd_) != 0) fail(path_, std::string("fsync failed: ") + std::strerror(errno));
  if (::close(fd_) != 0) {
    fd_ = -1;
    ::unlink(temp_.c_str());
    fail(path_, std::string("close failed: ") + std::strerror(errno));
  }
  fd_ = -1;
  if (::rename(temp_.c_str(), path_.c_str()) != 0) {
    int err = errno;
    ::unlink(temp_.c_str());
    fail(path_, std::string("rename failed: ") + std::strerror(err));
  }
  sync_directory_of(path_);
}

void write_file_atomically(const std::string& path, std::string_view content) {
  AtomicFile file(path);
  file.write(content);
  file.commit();
}

}  // namespace cellwalk
