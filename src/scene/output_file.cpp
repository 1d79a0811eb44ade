// OutputFile: write to a temporary name, fsync, rename (see output_file.hpp).
#include "scene/output_file.hpp"

#include <unistd.h>

#include <cerrno>
#include <cstdarg>
#include <cstring>

#include "cellwalk/error.hpp"

namespace cellwalk::detail {

OutputFile::OutputFile(std::string path) : path_(std::move(path)), tmp_(path_ + ".tmp") {
  file_ = std::fopen(tmp_.c_str(), "wb+");
  if (!file_) fail_io("cannot create");
}

OutputFile::~OutputFile() {
  if (file_) discard();
}

void OutputFile::fail_io(std::string_view what) const {
  fail(path_, std::string(what) + ": " + std::strerror(errno));
}

void OutputFile::write(const void* data, size_t size) {
  if (size > 0 && std::fwrite(data, 1, size, file_) != size) fail_io("write failed");
  size_ += size;
}

void OutputFile::print(const char* format, ...) {
  std::va_list args;
  va_start(args, format);
  const int n = std::vfprintf(file_, format, args);
  va_end(args);
  if (n < 0) fail_io("write failed");
  size_ += static_cast<uint64_t>(n);
}

void OutputFile::append_file(OutputFile& other) {
  if (std::fflush(other.file_) != 0 || std::fseek(other.file_, 0, SEEK_SET) != 0)
    other.fail_io("cannot reread");
  char buffer[1 << 16];
  for (size_t n; (n = std::fread(buffer, 1, sizeof buffer, other.file_)) > 0;) write(buffer, n);
  if (std::ferror(other.file_)) other.fail_io("read failed");
}

void OutputFile::commit() {
  if (std::fflush(file_) != 0 || ::fsync(fileno(file_)) != 0) fail_io("cannot flush");
  const int closed = std::fclose(file_);
  file_ = nullptr;
  if (closed != 0) fail_io("cannot close");
  if (std::rename(tmp_.c_str(), path_.c_str()) != 0) {
    const int saved = errno;
    std::remove(tmp_.c_str());
    errno = saved;
    fail_io("cannot rename the temporary file");
  }
}

void OutputFile::discard() {
  std::fclose(file_);
  file_ = nullptr;
  std::remove(tmp_.c_str());
}

}  // namespace cellwalk::detail
