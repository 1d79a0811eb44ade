// Writing files so that nothing is lost: bytes go to a temporary beside `path`, commit() fsyncs
// and renames it over `path`. Until commit() succeeds an existing file at `path` is untouched; a
// failure (e.g. a full disk) throws Error naming the file and removes the temporary.
//
// A killed process cannot remove its temporary, so each one is named after its process,
// ".<name>.cwtmp.<pid>": hidden, never ending in a file type cellwalk reads (a complete
// temporary of a world must not look like one), and recognisably stale once <pid> has exited.
// The first AtomicFile a process opens in a directory removes the temporaries there whose
// process no longer exists; a live process's temporary is never touched.
#pragma once

#include <sys/types.h>

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

// The temporary an AtomicFile for `path` writes in process `pid`: "<dir>/.<name>.cwtmp.<pid>".
std::string temporary_path(const std::string& path, pid_t pid);

}  // namespace cellwalk
