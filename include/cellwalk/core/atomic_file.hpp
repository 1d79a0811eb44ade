// Writing files so that nothing is lost: bytes go to "<path>.tmp.<pid>", commit() fsyncs and
// renames over `path`. Until commit() succeeds an existing file at `path` is untouched; a
// failure (e.g. a full disk) throws Error naming the file and removes the temporary.
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <string_view>

namespace cellwalk {

class AtomicFile {
 public:
  explicit AtomicFile(std::string path);
  ~AtomicFile();  // removes the temporary if commit() was not reached
  AtomicFile(const AtomicFile&) = delete;
  AtomicFile& operator=(const AtomicFile&) = delete;

  void write(std::span<const uint8_t> bytes);
  void write(std::string_view text) {
    write(std::span(reinterpret_cast<const uint8_t*>(text.data()), text.size()));
  }
  uint64_t size() const { return written_; }  // bytes written so far = offset of the next
  // Replaces bytes already written at [offset, offset + bytes.size()), e.g. a header whose
  // fields are known only at the end. REQUIRES: offset + bytes.size() <= size().
  void overwrite(uint64_t offset, std::span<const uint8_t> bytes);
  // Writes here everything written to `other` so far, e.g. a part staged in a scratch file
  // (never committed, so removed by its destructor) because a header before it could only be
  // written at the end. `other` is left as it was.
  void append_contents_of(AtomicFile& other);
  void commit();
  const std::string& path() const { return path_; }

 private:
  void flush();

  std::string path_;
  std::string temp_;
  int fd_ = -1;
  uint64_t written_ = 0;
  std::string buffer_;
};

void write_file_atomically(const std::string& path, std::string_view content);

}  // namespace cellwalk
