// A file written under "<path>.tmp" and renamed to <path> by commit(), so a failed or killed
// export never leaves a file at <path> that looks complete. Used by the model exporters.
#pragma once

#include <cstdio>
#include <string>
#include <string_view>

namespace cellwalk::detail {

class OutputFile {
 public:
  // Creates "<path>.tmp"; throws Error naming `path` if it cannot.
  explicit OutputFile(std::string path);
  ~OutputFile();  // removes the temporary file unless commit() succeeded
  OutputFile(const OutputFile&) = delete;
  OutputFile& operator=(const OutputFile&) = delete;

  void write(const void* data, size_t size);
  void write(std::string_view text) { write(text.data(), text.size()); }
  // printf-style text; throws Error on a write failure (e.g. a full disk).
  void print(const char* format, ...) __attribute__((format(printf, 2, 3)));
  uint64_t size() const { return size_; }
  // Copies the whole temporary file of `other` (which must be flushed by this call) here.
  void append_file(OutputFile& other);
  // Flushes, fsyncs, closes and renames to the final path.
  void commit();
  // Closes and removes the temporary file (for scratch files that are never committed).
  void discard();

 private:
  [[noreturn]] void fail_io(std::string_view what) const;

  std::string path_;
  std::string tmp_;
  std::FILE* file_ = nullptr;
  uint64_t size_ = 0;
};

}  // namespace cellwalk::detail
