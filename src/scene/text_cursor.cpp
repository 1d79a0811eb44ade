// TextCursor: the one tokenizer of the text model formats (OFF, ASCII PLY, OBJ).
#include <charconv>
#include <cstdlib>
#include <string>

#include "cellwalk/core/error.hpp"
#include "scene/readers.hpp"

namespace cellwalk::detail {

namespace {

bool is_blank(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\f' || c == '\v'; }

// from_chars rejects a leading '+', which OBJ and PLY writers emit.
std::string_view drop_plus(std::string_view token) {
  return token.size() > 1 && token[0] == '+' ? token.substr(1) : token;
}

}  // namespace

TextCursor::TextCursor(Bytes bytes, std::string name, char comment)
    : text_(reinterpret_cast<const char*>(bytes.data()), bytes.size()),
      name_(std::move(name)),
      comment_(comment) {
  check_not_utf16(bytes);
}

// Text saved as UTF-16 (Windows editors do) reads as one long token with NULs between the
// letters, which would be reported as a file without vertices; say what it is instead.
void TextCursor::check_not_utf16(Bytes bytes) const {
  if (bytes.size() < 2) return;
  const bool bom = (bytes[0] == 0xFF && bytes[1] == 0xFE) || (bytes[0] == 0xFE && bytes[1] == 0xFF);
  if (bom)
    fail("the file is UTF-16 text; convert it to UTF-8 (iconv -f UTF-16 -t UTF-8 IN > OUT) and import that");
  if (bytes[0] == 0 || bytes[1] == 0)
    fail("the file starts with NUL bytes: UTF-16 text without a byte-order mark, or not text; convert it to UTF-8 "
                       "(iconv -f UTF-16LE -t UTF-8 IN > OUT)");
}

void TextCursor::skip_blanks_in_line() {
  while (pos_ < text_.size() && is_blank(text_[pos_])) ++pos_;
  if (comment_ != '\0' && pos_ < text_.size() && text_[pos_] == comment_)
    while (pos_ < text_.size() && text_[pos_] != '\n') ++pos_;
}

std::string_view TextCursor::token() {
  for (;;) {
    skip_blanks_in_line();
    if (pos_ >= text_.size()) return {};
    if (text_[pos_] != '\n') return token_in_line();
    ++pos_;
    ++line_;
  }
}

std::string_view TextCursor::token_in_line() {
  skip_blanks_in_line();
  const size_t start = pos_;
  while (pos_ < text_.size() && !is_blank(text_[pos_]) && text_[pos_] != '\n' &&
         !(comment_ != '\0' && text_[pos_] == comment_))
    ++pos_;
  return text_.substr(start, pos_ - start);
}

void TextCursor::next_line() {
  while (pos_ < text_.size() && text_[pos_] != '\n') ++pos_;
  if (pos_ < text_.size()) {
    ++pos_;
    ++line_;
  }
}

std::string_view TextCursor::rest_of_line() {
  const size_t start = pos_;
  while (pos_ < text_.size() && text_[pos_] != '\n') ++pos_;
  std::string_view line = text_.substr(start, pos_ - start);
  if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
  return line;
}

double TextCursor::to_double(std::string_view token, std::string_view what) const {
  if (token.empty()) fail("expected " + std::string(what) + ", found the end of the line");
  token = drop_plus(token);
  double value = 0.0;
  auto [end, ec] = std::from_chars(token.data(), token.data() + token.size(), value);
  // from_chars leaves `value` unset when out of range; strtod gives the ±inf (or 0 on
  // underflow) that validate() then judges.
  if (ec == std::errc::result_out_of_range) return std::strtod(std::string(token).c_str(), nullptr);
  if (ec != std::errc() || end != token.data() + token.size())
    fail("expected " + std::string(what) + ", found '" + std::string(token.substr(0, 40)) + "'");
  return value;
}

int64_t TextCursor::to_int(std::string_view token, std::string_view what) const {
  if (token.empty()) fail("expected " + std::string(what) + ", found the end of the line");
  token = drop_plus(token);
  int64_t value = 0;
  auto [end, ec] = std::from_chars(token.data(), token.data() + token.size(), value);
  if (ec != std::errc() || end != token.data() + token.size())
    fail("expected " + std::string(what) + ", found '" + std::string(token.substr(0, 40)) + "'");
  return value;
}

uint64_t TextCursor::to_count(std::string_view token, std::string_view what,
                              size_t min_bytes_each) const {
  const int64_t value = to_int(token, what);
  if (value < 0) fail(std::string(what) + " " + std::to_string(value) + " is negative");
  const uint64_t count = static_cast<uint64_t>(value);
  if (min_bytes_each > 0 && count > remaining() / min_bytes_each)
    fail(std::string(what) + " " + std::to_string(count) + " cannot fit in the " +
         std::to_string(remaining()) + " bytes left (file truncated or count wrong)");
  return count;
}

std::string TextCursor::where() const { return name_ + ":" + std::to_string(line_); }

void TextCursor::fail(std::string_view what) const { cellwalk::fail(where(), what); }

}  // namespace cellwalk::detail
