// `cellwalk bench import`: see import_report.hpp.
#include "experiments/import/import_report.hpp"

#include <fcntl.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <array>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>

#include "cellwalk/core/atomic_file.hpp"
#include "cellwalk/core/error.hpp"
#include "core/progress.hpp"
#include "experiments/common/bench_support.hpp"

namespace cellwalk {
namespace {

namespace fs = std::filesystem;
using bench::fixed;
using Json = nlohmann::ordered_json;

// A side × side height field as a binary PLY, rows in order (as a scan's are), written row by row.
void write_height_field(const std::string& path, uint32_t side) {
  std::ofstream out(path, std::ios::binary);
  const uint64_t quads = uint64_t(side - 1) * (side - 1);
  out << "ply\nformat binary_little_endian 1.0\ncomment cellwalk bench import: a height field\nelement vertex "
      << uint64_t(side) * side << "\nproperty float x\nproperty float y\nproperty float z\nelement face " << 2 * quads
      << "\nproperty list uchar int vertex_indices\nend_header\n";
  std::vector<float> row(size_t(side) * 3);
  for (uint32_t z = 0; z < side; ++z) {
    for (uint32_t x = 0; x < side; ++x) {
      const float fx = float(x), fz = float(z);
      row[3 * x] = fx;
      row[3 * x + 1] = 3.0f * std::sin(0.05f * fx) * std::cos(0.07f * fz) + 0.5f * std::sin(0.31f * (fx + fz));
      row[3 * x + 2] = fz;
    }
    out.write(reinterpret_cast<const char*>(row.data()), std::streamsize(row.size() * sizeof(float)));
  }
  std::string faces;
  for (uint32_t z = 0; z + 1 < side; ++z) {
    faces.clear();
    for (uint32_t x = 0; x + 1 < side; ++x) {
      const int32_t a = int32_t(z * side + x), b = a + 1, c = a + int32_t(side), d = c + 1;
      const std::array<int32_t, 3> two[2] = {{a, c, b}, {b, c, d}};
      for (const std::array<int32_t, 3>& t : two) {
        faces += '\x03';
        faces.append(reinterpret_cast<const char*>(t.data()), sizeof t);
      }
    }
    out.write(faces.data(), std::streamsize(faces.size()));
  }
  if (!out.flush()) fail(path, "cannot write the bench's model (is the disk full? pass --work-dir)");
}

struct ChildRun {
  int exit_code = 0;
  std::string output;  // stdout
  uint64_t max_rss_bytes = 0;
  double seconds = 0.0;
};

// This binary run with `args` in a child; its peak resident memory from the kernel (wait4).
ChildRun run_self(const std::vector<std::string>& args) {
  int fds[2];
  if (::pipe(fds) != 0) fail("bench import", std::string("pipe: ") + std::strerror(errno));
  const auto start = bench::Clock::now();
  const pid_t pid = ::fork();
  if (pid < 0) fail("bench import", std::string("fork: ") + std::strerror(errno));
  if (pid == 0) {
    ::dup2(fds[1], STDOUT_FILENO);
    const int null = ::open("/dev/null", O_WRONLY);
    ::dup2(null, STDERR_FILENO);
    ::close(fds[0]);
    ::close(fds[1]);
    std::vector<char*> argv;
    static std::string self = "cellwalk";
    argv.push_back(self.data());
    for (const std::string& a : args) argv.push_back(const_cast<char*>(a.c_str()));
    argv.push_back(nullptr);
    ::execv("/proc/self/exe", argv.data());
    ::_exit(127);
  }
  ::close(fds[1]);
  ChildRun r;
  char buffer[4096];
  for (ssize_t n; (n = ::read(fds[0], buffer, sizeof buffer)) != 0;) {
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) break;
    r.output.append(buffer, size_t(n));
  }
  ::close(fds[0]);
  int status = 0;
  struct rusage usage {};
  while (::wait4(pid, &status, 0, &usage) < 0 && errno == EINTR) {
  }
  r.seconds = bench::seconds_since(start);
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  r.max_rss_bytes = uint64_t(usage.ru_maxrss) * 1024;
  return r;
}

std::string mib(double bytes) { return fixed(bytes / 1048576.0, 1); }

const std::vector<std::string> kHeader{"side",           "triangles",   "file MB", "mode",        "--memory MiB",
                                       "seconds",        "peak MiB",    "at start MiB", "peak − start MiB",
                                       "within memory", "objects"};

}  // namespace

Json run_import_bench(const ImportBenchParams& p) {
  const auto start = bench::Clock::now();
  const Json machine = bench::machine_info();
  bench::WorkDir work(p.work_dir, "import");
  std::vector<uint32_t> sides = p.sides;
  if (p.large) sides.push_back(9000);
  bench::Table rows;
  Json runs = Json::array();
  Progress progress("bench import", sides.size() * (p.memory_mib.size() + 1));
  uint64_t done = 0;
  for (uint32_t side : sides) {
    const std::string model = work.file("field" + std::to_string(side) + ".ply");
    write_height_field(model, side);
    const uint64_t file_bytes = fs::file_size(model);
    const uint64_t triangles = 2ull * (side - 1) * (side - 1);
    // Read whole first (never streamed: --memory far above the file), then streamed at each memory.
    std::vector<double> memories = {0.0};
    memories.insert(memories.end(), p.memory_mib.begin(), p.memory_mib.end());
    for (double memory : memories) {
      const bool streamed = memory > 0.0;
      std::vector<std::string> args = {"import", model, "-o", work.file("field.cwscene"), "--json", "--memory",
                                       streamed ? std::to_string(memory) : "1048576"};
      if (streamed) args.push_back("--stream");
      Json run = {{"side", side}, {"triangles", triangles}, {"file_bytes", file_bytes},
                  {"mode", streamed ? "streamed" : "whole"}, {"memory_mib", memory}};
      std::vector<std::string> row = {std::to_string(side), std::to_string(triangles), fixed(file_bytes / 1e6, 0),
                                      streamed ? "streamed" : "read whole", streamed ? fixed(memory, 0) : "–"};
      if (!streamed && file_bytes > (uint64_t(2) << 30)) {
        row.insert(row.end(), {"–", "–", "–", "–", "–", "refused: over 2 GiB read whole"});
        run["refused"] = true;
      } else {
        const ChildRun r = run_self(args);
        if (r.exit_code != 0) fail("bench import", "cellwalk " + args[0] + " " + model + " failed (exit " + std::to_string(r.exit_code) + ")");
        const Json j = Json::parse(r.output.substr(std::min(r.output.find('{'), r.output.size())), nullptr, false);
        const uint64_t baseline = j.is_object() ? j.value("baseline_rss_bytes", uint64_t(0)) : 0;
        const uint64_t objects = j.is_object() ? j.value("objects", uint64_t(0)) : 0;
        const bool within = streamed && r.max_rss_bytes <= baseline + uint64_t(memory * 1048576.0);
        row.insert(row.end(), {fixed(r.seconds, 1), mib(double(r.max_rss_bytes)), mib(double(baseline)),
                               mib(double(r.max_rss_bytes) - double(baseline)), streamed ? (within ? "yes" : "**no**") : "–",
                               std::to_string(objects)});
        run.update({{"seconds", r.seconds}, {"peak_rss_bytes", r.max_rss_bytes}, {"baseline_rss_bytes", baseline},
                    {"within_memory", within}, {"objects", objects}});
      }
      rows.push_back(row);
      runs.push_back(run);
      progress.update(++done);
    }
    fs::remove(model);
    fs::remove(work.file("field.cwscene"));
  }
  progress.finish();
  const double seconds = bench::seconds_since(start);
  std::string md = "# Importing a model larger than memory\n\n";
  md += "Generated by `" + p.command_line + "` on " + bench::utc_now() + " in " + fixed(seconds / 60.0, 1) +
        " min; machine: " + machine.dump() + ".\n\n";
  md += "Each model is a height field of side × side vertices in a binary PLY, rows in order (as a scan's), imported "
        "by `cellwalk import` in a child process: read whole, then streamed (`--stream --memory M`, docs/import.md). "
        "*Peak* is the child's peak resident memory as the kernel measures it from outside (wait4); *at start* its "
        "resident memory before it reads the model (its `--json`); a streamed import keeps peak − start within "
        "`--memory` whatever the model's size, where reading whole grows with it. A file over 2 GiB is not read "
        "whole at all. Scratch files go beside the output.\n\n";
  md += bench::md_table(kHeader, rows, bench::Align::kFigures);
  const fs::path out(p.out_dir);
  fs::create_directories(out / "import");
  bench::write_csv(out / "import" / "runs.csv", kHeader, rows);
  write_file_atomically((out / "import.md").string(), md);
  return {{"runs", runs}, {"seconds", seconds}};
}

}  // namespace cellwalk
