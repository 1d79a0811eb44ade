#include "test_support.hpp"

#include <gtest/gtest.h>
#include <fcntl.h>
#include <sys/file.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>

#include <array>
#include <fstream>
#include <atomic>
#include <cstdio>
#include <cstdlib>
#include <unistd.h>

namespace cellwalk::test {

std::string source_path(const std::string& relative) {
  return std::string(CELLWALK_SOURCE_DIR) + "/" + relative;
}

std::string cgal_mesh(const std::string& name) {
  std::string p = source_path("data/cgal/meshes/" + name);
  if (!std::filesystem::exists(p))
    ADD_FAILURE() << p << " is missing: run scripts/setup to unpack libcgal-demo's data";
  return p;
}

std::string assimp_model(const std::string& relative) {
  std::string p = "/usr/share/assimp/models/" + relative;
  if (!std::filesystem::exists(p))
    ADD_FAILURE() << p << " is missing: run scripts/setup to install assimp-testmodels";
  return p;
}

std::vector<uint8_t> slurp(const std::string& file) {
  std::ifstream in(file, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), {}};
}

void spit(const std::string& file, const std::vector<uint8_t>& bytes) {
  std::ofstream out(file, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
}

TempDir::TempDir() {
  static std::atomic<int> counter{0};
  path_ = std::filesystem::temp_directory_path() /
          ("cellwalk-test-" + std::to_string(getpid()) + "-" + std::to_string(counter++));
  std::filesystem::remove_all(path_);
  std::filesystem::create_directories(path_);
}

TempDir::~TempDir() {
  std::error_code ec;
  std::filesystem::remove_all(path_, ec);
}

std::string cellwalk_binary() {
  const char* other = std::getenv("CELLWALK_BINARY");
  return other && *other ? other : CELLWALK_BINARY;
}

nlohmann::json json_output(const CommandResult& r) {
  const size_t start = r.output.find('{');
  if (start == std::string::npos) return nullptr;
  nlohmann::json j = nlohmann::json::parse(r.output.substr(start), nullptr, false);
  return j.is_discarded() ? nlohmann::json() : j;
}

nlohmann::json only_run(const CommandResult& r) {
  const nlohmann::json j = json_output(r);
  if (!j.is_object() || !j.contains("runs") || !j["runs"].is_array() || j["runs"].size() != 1) return nullptr;
  return j["runs"][0];
}

CommandResult run_cellwalk(const std::string& args) {
  CommandResult result;
  // Appended piece by piece: GCC 12 misreads `std::string(literal) + ...` as out of bounds.
  std::string command = cellwalk_binary();
  command.append(" ").append(args).append(" 2>&1");
  // fork + exec rather than popen, so wait4 reports the command's peak memory from outside it.
  int fds[2];
  if (pipe(fds) != 0) return {-1, "pipe failed", 0};
  const pid_t child = fork();
  if (child == 0) {
    dup2(fds[1], STDOUT_FILENO);
    close(fds[0]);
    close(fds[1]);
    execl("/bin/sh", "sh", "-c", command.c_str(), static_cast<char*>(nullptr));
    _exit(127);
  }
  close(fds[1]);
  std::array<char, 4096> buffer;
  ssize_t n;
  while ((n = read(fds[0], buffer.data(), buffer.size())) > 0) result.output.append(buffer.data(), size_t(n));
  close(fds[0]);
  int status = 0;
  rusage usage{};
  if (child < 0 || wait4(child, &status, 0, &usage) != child) return {-1, result.output, 0};
  result.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  result.max_rss_bytes = uint64_t(usage.ru_maxrss) * 1024;  // ru_maxrss is in KiB on Linux
  return result;
}

namespace {

uint64_t fnv1a(const std::string& text) {
  uint64_t h = 14695981039346656037ull;
  for (const char c : text) h = (h ^ uint8_t(c)) * 1099511628211ull;
  return h;
}

// What a rebuilt binary changes: its path, size and modification time.
std::string binary_identity(const std::string& binary) {
  struct stat st {};
  if (stat(binary.c_str(), &st) != 0) return binary;
  return binary + " " + std::to_string(st.st_size) + " " + std::to_string(st.st_mtim.tv_sec) + "." +
         std::to_string(st.st_mtim.tv_nsec);
}

std::string with_dir(std::string command, const std::string& dir) {
  for (size_t at = command.find("{dir}"); at != std::string::npos; at = command.find("{dir}", at + dir.size()))
    command.replace(at, 5, dir);
  return command;
}

// Removes the folders an earlier binary made for `name`: they would only fill the disk.
void remove_stale(const std::filesystem::path& root, const std::string& name, const std::filesystem::path& keep) {
  std::error_code ec;
  for (const auto& entry : std::filesystem::directory_iterator(root, ec)) {
    const std::string leaf = entry.path().filename().string();
    if (entry.path() != keep && leaf.size() == name.size() + 17 && leaf.rfind(name + "-", 0) == 0 && entry.is_directory(ec))
      std::filesystem::remove_all(entry.path(), ec);
  }
}

}  // namespace

SharedInputs::SharedInputs(const std::string& name, const std::vector<std::string>& commands) {
  std::string key = binary_identity(cellwalk_binary());
  for (const std::string& c : commands) key.append("\n").append(c);
  char hash[17];
  std::snprintf(hash, sizeof hash, "%016llx", static_cast<unsigned long long>(fnv1a(key)));
  const std::filesystem::path root = std::filesystem::read_symlink("/proc/self/exe").parent_path() / "test-inputs";
  std::filesystem::create_directories(root);
  path_ = root / (name + "-" + hash);
  const int lock = open((path_.string() + ".lock").c_str(), O_CREAT | O_RDWR | O_CLOEXEC, 0644);
  if (lock < 0 || flock(lock, LOCK_EX) != 0) {
    ADD_FAILURE() << "cannot lock " << path_ << ".lock";
    if (lock >= 0) close(lock);
    return;
  }
  complete_ = std::filesystem::exists(path_ / ".complete");
  if (!complete_) {
    remove_stale(root, name, path_);
    std::filesystem::remove_all(path_);
    std::filesystem::create_directories(path_);
    complete_ = true;
    for (const std::string& c : commands) {
      const std::string command = with_dir(c, path_.string());
      const CommandResult r = run_cellwalk(command);
      if (r.exit_code != 0) {
        ADD_FAILURE() << "making the shared inputs " << name << ": cellwalk " << command << "\n" << r.output;
        complete_ = false;
        break;
      }
    }
    if (complete_) std::ofstream(path_ / ".complete") << key;
  }
  flock(lock, LOCK_UN);
  close(lock);
}

}  // namespace cellwalk::test

#include "cellwalk/core/random.hpp"
#include "cellwalk/scene/scene_file.hpp"
#include "cellwalk/store/world.hpp"

namespace cellwalk::test {

Mesh box_mesh(const Aabb& b) {
  Mesh m;
  const Vec3 n[6] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
  for (int f = 0; f < 6; ++f) {
    // Two tangent axes of the face, ordered so triangles wind counter-clockwise seen from outside.
    const Vec3 u = std::abs(n[f].y) > 0 ? Vec3(1, 0, 0) : Vec3(0, 1, 0);
    const Vec3 v = glm::cross(n[f], u);
    const Vec3 c = b.center() + n[f] * (b.size() * 0.5f);
    const Vec3 hu = u * (b.size() * 0.5f), hv = v * (b.size() * 0.5f);
    const uint32_t base = static_cast<uint32_t>(m.positions.size());
    for (Vec3 p : {c - hu - hv, c + hu - hv, c + hu + hv, c - hu + hv}) {
      m.positions.push_back(p);
      m.normals.push_back(n[f]);
    }
    for (uint32_t i : {0u, 1u, 2u, 0u, 2u, 3u}) m.indices.push_back(base + i);
  }
  return m;
}

Mesh quad_mesh(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
  Mesh m;
  const Vec3 n = glm::normalize(glm::cross(b - a, c - a));
  for (const Vec3& p : {a, b, c, d}) {
    m.positions.push_back(p);
    m.normals.push_back(n);
  }
  m.indices = {0, 1, 2, 0, 2, 3};
  return m;
}

Mesh double_sided(const Mesh& mesh) {
  Mesh back = mesh;
  for (Vec3& n : back.normals) n = -n;
  for (size_t t = 0; t + 2 < back.indices.size(); t += 3) std::swap(back.indices[t + 1], back.indices[t + 2]);
  Mesh out = mesh;
  append(out, back);
  return out;
}

Mesh double_sided_room_with_door() {
  const float w = 10, h = 3, door_lo = 4, door_hi = 6, door_top = 2.2f;
  Mesh m;
  for (const Mesh& q : {quad_mesh({0, 0, 0}, {0, 0, w}, {w, 0, w}, {w, 0, 0}),        // floor
                        quad_mesh({0, h, 0}, {w, h, 0}, {w, h, w}, {0, h, w}),        // ceiling
                        quad_mesh({0, 0, 0}, {0, h, 0}, {0, h, w}, {0, 0, w}),        // x = 0
                        quad_mesh({w, 0, 0}, {w, 0, w}, {w, h, w}, {w, h, 0}),        // x = 10
                        quad_mesh({0, 0, w}, {0, h, w}, {w, h, w}, {w, 0, w}),        // z = 10
                        quad_mesh({0, 0, 0}, {door_lo, 0, 0}, {door_lo, h, 0}, {0, h, 0}),  // z = 0 ...
                        quad_mesh({door_hi, 0, 0}, {w, 0, 0}, {w, h, 0}, {door_hi, h, 0}),
                        quad_mesh({door_lo, door_top, 0}, {door_hi, door_top, 0}, {door_hi, h, 0},
                                  {door_lo, h, 0})})  // ... around the doorway
    append(m, double_sided(q));
  return m;
}

std::string write_street_scene(const TempDir& dir, int count, uint64_t seed) {
  const std::string file = dir.file("street-" + std::to_string(seed) + ".cwscene");
  Random rng(seed);
  SceneWriter writer(file);
  float length = 0;
  for (int i = 0; i < count; ++i) {
    const float side = (i % 2) ? 1.0f : -1.0f;
    const float x = 6.0f * static_cast<float>(i / 2);
    const float w = static_cast<float>(rng.uniform(2, 5)), h = static_cast<float>(rng.uniform(3, 20));
    const float z0 = side * static_cast<float>(rng.uniform(4, 8));
    Aabb box;
    box.min = Vec3(x, 0, std::min(z0, z0 + side * w));
    box.max = Vec3(x + w, h, std::max(z0, z0 + side * w));
    Object o;
    o.id = static_cast<ObjectId>(i);
    o.name = "box" + std::to_string(i);
    o.color = rgba8(static_cast<uint8_t>(rng.integer(40, 255)), static_cast<uint8_t>(rng.integer(40, 255)),
                    static_cast<uint8_t>(rng.integer(40, 255)));
    o.mesh = box_mesh(box);
    o.bounds = box;
    writer.add(o);
    length = std::max(length, box.max.x);
  }
  SceneInfo info;
  info.generator = "test-street";
  info.seed = seed;
  info.nav.nodes = {Vec3(-5, 1.7f, 0), Vec3(length + 5, 1.7f, 0)};
  info.nav.edges = {{0, 1}};
  writer.finish(info);
  return file;
}

std::string write_street_world(const TempDir& dir, int count, uint64_t seed) {
  const std::string scene = write_street_scene(dir, count, seed);
  const std::string world = dir.file("street-" + std::to_string(seed) + ".cww");
  build_world(scene, world, BuildParams{});
  return world;
}

}  // namespace cellwalk::test

namespace cellwalk::test {

std::string write_world(const TempDir& dir, const std::vector<Object>& objects, const NavGraph& nav,
                        const std::string& name) {
  const std::string scene = dir.file(name + ".cwscene");
  const std::string world = dir.file(name + ".cww");
  SceneWriter writer(scene);
  for (Object o : objects) {
    o.bounds = bounds_of(o.mesh);
    writer.add(o);
  }
  SceneInfo info;
  info.generator = "test-objects";
  info.nav = nav;
  writer.finish(info);
  build_world(scene, world, BuildParams{});
  return world;
}

}  // namespace cellwalk::test
