// The checks every command shares on what a user gives it (checks.hpp).
#include "checks.hpp"

#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>

#include "cellwalk/core/error.hpp"
#include "cellwalk/scene/path_generator.hpp"

namespace cellwalk::app {

namespace {

// Bounds as a person writes them: "0.05", "1e+06", never 300 digits.
std::string readable(double v) {
  char text[32];
  std::snprintf(text, sizeof text, "%.6g", v);
  return text;
}

// FNV-1a: a stable hash of bytes, the same on every machine and build.
void hash_bytes(uint64_t& h, const void* data, size_t n) {
  const auto* p = static_cast<const uint8_t*>(data);
  for (size_t i = 0; i < n; ++i) h = (h ^ p[i]) * 1099511628211ull;
}

// Two spellings of one file: equal inodes when both exist, else equal normalised paths.
bool same_file(const std::string& a, const std::string& b) {
  std::error_code ec;
  if (std::filesystem::exists(a, ec) && std::filesystem::exists(b, ec)) return std::filesystem::equivalent(a, b, ec);
  return std::filesystem::weakly_canonical(a, ec) == std::filesystem::weakly_canonical(b, ec);
}

}  // namespace

CLI::Validator number_in(double lo, double hi, bool open_low) {
  const std::string range = (open_low ? "(" : "[") + readable(lo) + ", " + readable(hi) + "]";
  return CLI::Validator(
      [=](std::string& text) -> std::string {
        char* end = nullptr;
        const double v = std::strtod(text.c_str(), &end);
        if (text.empty() || *end != '\0') return "'" + text + "' is not a number";
        if (!std::isfinite(v)) return "'" + text + "' is not a finite number; give one in " + range;
        if (v < lo || v > hi || (open_low && v == lo)) return text + " is outside " + range;
        return {};
      },
      "in " + range);
}

CLI::Validator integer_in(int64_t lo, int64_t hi) {
  const std::string range = "[" + std::to_string(lo) + ", " + std::to_string(hi) + "]";
  return CLI::Validator(
      [=](std::string& text) -> std::string {
        int64_t v = 0;
        const char* end = text.data() + text.size();
        const auto [stop, error] = std::from_chars(text.data(), end, v);
        if (error == std::errc::result_out_of_range) return text + " is outside " + range;
        if (error != std::errc() || stop != end) return "'" + text + "' is not a whole number";
        if (v < lo || v > hi) return text + " is outside " + range;
        return {};
      },
      "in " + range);
}

CLI::Validator thread_count() { return integer_in(0, kMaxThreads).description("0 (all cores) to " + std::to_string(kMaxThreads)); }

CLI::Validator session_kind_check() {
  return CLI::Validator(
      [](std::string& kind) -> std::string {
        try {
          parse_session_kind(kind);
          return {};
        } catch (const Error& e) {
          return e.what();
        }
      },
      "a path kind");
}

CLI::Validator page_size_check() {
  return CLI::Validator(
      [](std::string& text) -> std::string {
        uint64_t v = 0;
        const char* end = text.data() + text.size();
        const auto [stop, error] = std::from_chars(text.data(), end, v);
        if (error != std::errc() || stop != end || v < 512 || v > (1u << 20) || (v & (v - 1)) != 0)
          return "page size " + text + " is not a power of two from 512 to 1048576 bytes (e.g. 4096)";
        return {};
      },
      "a power of two, 512 to 1048576");
}

void refuse_same_files(const std::vector<std::string>& inputs, const std::vector<std::string>& outputs) {
  for (size_t o = 0; o < outputs.size(); ++o) {
    if (outputs[o].empty()) continue;
    for (const std::string& input : inputs)
      if (!input.empty() && same_file(input, outputs[o]))
        fail(outputs[o], "is the same file as the input " + input + "; writing it would destroy the input, so give another output path");
    for (size_t p = 0; p < o; ++p)
      if (!outputs[p].empty() && same_file(outputs[p], outputs[o]))
        fail(outputs[o], "is the same file as the output " + outputs[p] + "; give each output its own path");
  }
}

OutputFolder::OutputFolder(const std::string& folder) {
  namespace fs = std::filesystem;
  fs::path p = fs::absolute(folder).lexically_normal();
  if (p.filename().empty()) p = p.parent_path();  // "out/walk/"
  for (; !fs::exists(p); p = p.parent_path()) {
    created_.push_back(p.string());
    if (p == p.parent_path()) break;
  }
  std::error_code ec;
  fs::create_directories(folder, ec);
  if (ec || !fs::is_directory(folder)) {
    remove_empty();
    fail(folder, "cannot create the output folder: " + (ec ? ec.message() : std::string("a file has that name")) +
                     "; give another --output");
  }
}

OutputFolder::~OutputFolder() { remove_empty(); }

void OutputFolder::remove_empty() {
  std::error_code ec;
  for (const std::string& p : created_)
    if (!std::filesystem::is_empty(p, ec) || ec || !std::filesystem::remove(p, ec)) break;
  created_.clear();
}

PathWorld path_world(const SceneInfo& info) {
  uint64_t h = 14695981039346656037ull;
  hash_bytes(h, info.generator.data(), info.generator.size());
  hash_bytes(h, &info.seed, sizeof info.seed);
  for (const Vec3& n : info.nav.nodes) hash_bytes(h, &n, sizeof n);
  for (const auto& [a, b] : info.nav.edges) {
    hash_bytes(h, &a, sizeof a);
    hash_bytes(h, &b, sizeof b);
  }
  char identity[17];
  std::snprintf(identity, sizeof identity, "%016llx", static_cast<unsigned long long>(h));
  std::string name = info.generator.empty() ? "unnamed" : info.generator;
  for (char& c : name)
    if (c == '\n' || c == '\r') c = ' ';
  return {name, identity};
}

void warn_if_other_world(const CameraPath& path, const std::string& path_file, const SceneInfo& info,
                         const std::string& world_file) {
  if (!path.world.known()) return;
  const PathWorld here = path_world(info);
  if (here.identity == path.world.identity) return;
  warn(path_file, "made for the world '" + path.world.name + "' (" + path.world.identity + "), not " + world_file +
                      " ('" + here.name + "', " + here.identity +
                      "); its frames may stand inside buildings: make a path for this world with cellwalk path");
}

}  // namespace cellwalk::app
