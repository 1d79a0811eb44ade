// What every `cellwalk bench <name>` shares (DESIGN.md "Measuring"): the report header's date
// and machine, the work directory for generated scenes and worlds, number formatting,
// markdown / CSV tables of strings, and a strategy's frame with rendering modelled.
#pragma once

#include <chrono>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "cellwalk/core/camera.hpp"
#include "cellwalk/strategy/strategy.hpp"

namespace cellwalk::bench {

using Clock = std::chrono::steady_clock;
using Table = std::vector<std::vector<std::string>>;  // rows of cells

double seconds_since(Clock::time_point start);

// `v` with `digits` digits after the point ("%.*f").
std::string fixed(double v, int digits);

// Now, as "YYYY-MM-DD HH:MM UTC".
std::string utc_now();

// The 1-minute load average: on a shared machine it says how much else competed for the cores.
double load_average();

// {nproc, cpu, memory_bytes, load_average}: the report header's machine.
nlohmann::ordered_json machine_info();

// Mean and population variance; 0 for an empty vector.
double mean(const std::vector<double>& v);
double variance(const std::vector<double>& v);

// How a markdown table aligns its columns: as the renderer likes, or, for a table of figures,
// the first column (the row's name) left and the figures right.
enum class Align { kDefault, kFigures };

// A markdown table: a header row, the separator, one line per row.
std::string md_table(const std::vector<std::string>& header, const Table& rows, Align align = Align::kDefault);

// A CSV file (cells written as they are: the caller keeps commas out), written atomically.
void write_csv(const std::filesystem::path& file, const std::vector<std::string>& header, const Table& rows);

// Rows of JSON values as CSV cells: strings quoted (RFC 4180: inner quotes doubled), numbers as
// JSON writes them, null empty.
Table csv_cells(const nlohmann::ordered_json& rows);

// One frame of `s` at `camera` without rendering: the measured time of its select and mesh calls
// (query, I/O, decode) and the triangles it would draw, which a bench turns into modelled render
// time, the same for every strategy. `time` is the path's time (strategies derive speed from it).
struct SelectedFrame {
  double select_ms = 0.0;
  uint64_t triangles = 0;
};
SelectedFrame select_frame(Strategy& s, const Camera& camera, double time);

// Where a bench puts its scene, world and side files: `dir` when given (kept), else a fresh
// temporary directory "cellwalk-bench-<name>-<pid>" removed when the WorkDir goes.
class WorkDir {
 public:
  WorkDir(const std::string& dir, const std::string& name);
  ~WorkDir();
  WorkDir(const WorkDir&) = delete;
  WorkDir& operator=(const WorkDir&) = delete;

  const std::filesystem::path& path() const { return path_; }
  std::string file(const std::string& name) const { return (path_ / name).string(); }

 private:
  bool owned_;
  std::filesystem::path path_;
};

}  // namespace cellwalk::bench
