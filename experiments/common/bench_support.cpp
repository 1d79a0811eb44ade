// What every `cellwalk bench <name>` shares (DESIGN.md "Measuring"); see bench_support.hpp.
#include "experiments/common/bench_support.hpp"

#include <unistd.h>

#include <ctime>
#include <fstream>
#include <limits>
#include <numeric>
#include <thread>

#include "cellwalk/core/atomic_file.hpp"
#include "core/stopwatch.hpp"

namespace cellwalk::bench {
namespace {

std::string cpu_model() {
  std::ifstream in("/proc/cpuinfo");
  for (std::string line; std::getline(in, line);) {
    if (line.rfind("model name", 0) == 0) return line.substr(line.find(':') + 2);
  }
  return "unknown";
}

uint64_t memory_total_bytes() {
  std::ifstream in("/proc/meminfo");
  std::string key;
  uint64_t kib = 0;
  while (in >> key >> kib) {
    if (key == "MemTotal:") return kib * 1024;
    in.ignore(std::numeric_limits<std::streamsize>::max(), '\n');
  }
  return 0;
}

// The cells of one row joined by `separator`, between `open` and `close`.
std::string joined(const std::vector<std::string>& cells, const char* open, const char* separator,
                   const char* close) {
  std::string line = open;
  for (size_t i = 0; i < cells.size(); ++i) line += (i ? separator : "") + cells[i];
  return line + close;
}

}  // namespace

double seconds_since(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

std::string fixed(double v, int digits) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", digits, v);
  return buf;
}

std::string utc_now() {
  const std::time_t now = std::time(nullptr);
  std::tm tm{};
  gmtime_r(&now, &tm);
  char buf[32];
  std::strftime(buf, sizeof buf, "%Y-%m-%d %H:%M UTC", &tm);
  return buf;
}

double load_average() {
  std::ifstream in("/proc/loadavg");
  double load = 0.0;
  in >> load;
  return load;
}

nlohmann::ordered_json machine_info() {
  return {{"nproc", std::thread::hardware_concurrency()},
          {"cpu", cpu_model()},
          {"memory_bytes", memory_total_bytes()},
          {"load_average", load_average()}};
}

double mean(const std::vector<double>& v) {
  return v.empty() ? 0.0 : std::accumulate(v.begin(), v.end(), 0.0) / double(v.size());
}

double variance(const std::vector<double>& v) {
  const double m = mean(v);
  double s = 0.0;
  for (double x : v) s += (x - m) * (x - m);
  return v.empty() ? 0.0 : s / double(v.size());
}

std::string md_table(const std::vector<std::string>& header, const Table& rows, Align align) {
  std::string t = joined(header, "| ", " | ", " |\n") + "|";
  for (size_t i = 0; i < header.size(); ++i) t += align == Align::kDefault ? "---|" : i ? " ---: |" : " --- |";
  t += "\n";
  for (const auto& row : rows) t += joined(row, "| ", " | ", " |\n");
  return t;
}

void write_csv(const std::filesystem::path& file, const std::vector<std::string>& header, const Table& rows) {
  std::string text = joined(header, "", ",", "\n");
  for (const auto& row : rows) text += joined(row, "", ",", "\n");
  write_file_atomically(file.string(), text);
}

Table csv_cells(const nlohmann::ordered_json& rows) {
  Table table;
  for (const auto& row : rows) {
    std::vector<std::string>& cells = table.emplace_back();
    for (const auto& cell : row) {
      if (cell.is_null()) {
        cells.emplace_back();
      } else if (!cell.is_string()) {
        cells.push_back(cell.dump());
      } else {
        std::string quoted = "\"";
        for (char c : cell.get<std::string>()) quoted += c == '"' ? "\"\"" : std::string(1, c);
        cells.push_back(quoted + "\"");
      }
    }
  }
  return table;
}

WorkDir::WorkDir(const std::string& dir, const std::string& name) : owned_(dir.empty()) {
  path_ = owned_ ? std::filesystem::temp_directory_path() / ("cellwalk-bench-" + name + "-" + std::to_string(::getpid()))
                 : std::filesystem::path(dir);
  std::filesystem::create_directories(path_);
}

WorkDir::~WorkDir() {
  std::error_code ignored;
  if (owned_) std::filesystem::remove_all(path_, ignored);
}

SelectedFrame select_frame(Strategy& s, const Camera& camera, double time) {
  std::vector<DrawItem> items;
  FrameStats stats;
  stats.time = time;
  Stopwatch watch;
  s.select(camera, items, stats);
  SelectedFrame f;
  for (const DrawItem& item : items)
    if (const Mesh* m = s.mesh(item, stats)) f.triangles += m->triangle_count();
  f.select_ms = watch.ms();
  return f;
}

}  // namespace cellwalk::bench
