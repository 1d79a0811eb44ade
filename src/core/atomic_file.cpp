#include "cellwalk/core/atomic_file.hpp"

#include <fcntl.h>
#include <signal.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cstring>
#include <filesystem>
#include <mutex>
#include <set>

#include "cellwalk/core/error.hpp"

namespace cellwalk {
namespace {

constexpr size_t kBufferBytes = 1 << 20;
constexpr std::string_view kTemporaryTag = ".cwtmp.";

std::filesystem::path directory_of(const std::string& path) {
  std::filesystem::path dir = std::filesystem::path(path).parent_path();
  return dir.empty() ? "." : dir;
}

// The pid in a temporary's name ".<name>.cwtmp.<pid>", or 0 when `file` is no such name. Never
// negative: kill() with a pid <= 0 signals whole process groups.
pid_t temporary_pid(std::string_view file) {
  const size_t tag = file.rfind(kTemporaryTag);
  if (file.size() < 2 || file[0] != '.' || tag == std::string_view::npos || tag < 2) return 0;
  const std::string_view digits = file.substr(tag + kTemporaryTag.size());
  pid_t pid = 0;
  const auto [end, error] = std::from_chars(digits.data(), digits.data() + digits.size(), pid);
  return error == std::errc() && end == digits.data() + digits.size() && pid > 0 ? pid : 0;
}

bool process_has_exited(pid_t pid) { return ::kill(pid, 0) != 0 && errno == ESRCH; }

// Removes the temporaries in `dir` that killed processes left behind. Once per directory and
// process: a directory of many outputs (a walk's frames) is not listed again for each.
void remove_stale_temporaries(const std::filesystem::path& dir) {
  static std::mutex mutex;
  static std::set<std::filesystem::path> cleaned;
  std::error_code ec;
  const std::filesystem::path key = std::filesystem::absolute(dir, ec).lexically_normal();
  {
    std::lock_guard lock(mutex);
    if (ec || !cleaned.insert(key).second) return;
  }
  for (std::filesystem::directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec)) {
    const pid_t pid = temporary_pid(it->path().filename().native());
    std::error_code type_ec;
    if (pid > 0 && it->is_regular_file(type_ec) && process_has_exited(pid)) ::unlink(it->path().c_str());
  }
}

void sync_directory_of(const std::string& path) {
  int fd = ::open(directory_of(path).c_str(), O_RDONLY | O_DIRECTORY);
  if (fd >= 0) {
    ::fsync(fd);  // best effort: some file systems refuse fsync on directories
    ::close(fd);
  }
}

}  // namespace

AtomicFile::AtomicFile(std::string path) : path_(std::move(path)) {
  if (std::filesystem::is_directory(path_)) fail(path_, "is a directory, expected a file name");
  remove_stale_temporaries(directory_of(path_));
  temp_ = temporary_path(path_, ::getpid());
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

std::string temporary_path(const std::string& path, pid_t pid) {
  const std::filesystem::path p(path);
  const std::string name = "." + p.filename().string() + std::string(kTemporaryTag) + std::to_string(pid);
  return (p.parent_path() / name).string();
}

void write_file_atomically(const std::string& path, std::string_view content) {
  AtomicFile file(path);
  file.write(content);
  file.commit();
}

}  // namespace cellwalk
