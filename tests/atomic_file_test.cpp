// Temporaries of atomic writes (tracker issue 13, item 11): a killed run leaves its temporary
// behind; its name must not look like an output, and the next write into the directory removes
// it once its process is gone, never one whose process still runs.
#include "cellwalk/core/atomic_file.hpp"

#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <filesystem>

#include "test_support.hpp"

namespace cellwalk {
namespace {

namespace fs = std::filesystem;

// A process that has exited and been reaped: its pid names no process (until reused, which
// takes the kernel a full turn of the pid space).
pid_t exited_pid() {
  const pid_t child = ::fork();
  if (child == 0) ::_exit(0);
  ::waitpid(child, nullptr, 0);
  return child;
}

// A child that sleeps until killed.
pid_t sleeping_child() {
  const pid_t child = ::fork();
  if (child == 0)
    for (;;) ::pause();
  return child;
}

void stop(pid_t child) {
  ::kill(child, SIGKILL);
  ::waitpid(child, nullptr, 0);
}

TEST(AtomicFile, TemporaryIsHiddenAndLooksLikeNoOutput) {
  test::TempDir dir;
  for (const std::string name : {"w.cww", "s.cwscene", "m.obj", "w.cww.hdov"}) {
    const fs::path temp = temporary_path(dir.file(name), 4242);
    EXPECT_EQ(temp.parent_path(), dir.path());
    EXPECT_EQ(temp.filename().string(), "." + name + ".cwtmp.4242");
    for (const std::string ext : {".cww", ".cwscene", ".obj", ".hdov", ".tmp"})
      EXPECT_FALSE(temp.string().ends_with(ext)) << temp;
  }
  EXPECT_EQ(temporary_path("w.cww", 7), ".w.cww.cwtmp.7");
  // While a write is under way, the only file in the directory is that temporary.
  AtomicFile file(dir.file("w.cww"));
  file.write(std::string_view("bytes"));
  std::vector<std::string> names;
  for (const auto& entry : fs::directory_iterator(dir.path())) names.push_back(entry.path().filename().string());
  EXPECT_EQ(names, std::vector<std::string>{".w.cww.cwtmp." + std::to_string(::getpid())});
  file.commit();
  EXPECT_TRUE(fs::exists(dir.file("w.cww")));
  EXPECT_FALSE(fs::exists(temporary_path(dir.file("w.cww"), ::getpid())));
}

TEST(AtomicFile, StaleTemporariesOfExitedProcessesAreRemovedByTheNextWrite) {
  test::TempDir dir;
  const pid_t gone = exited_pid();
  const pid_t alive = sleeping_child();
  // Stale: a killed build's complete world and a killed import's scene, both of `gone`.
  const std::string stale_world = temporary_path(dir.file("w.cww"), gone);
  const std::string stale_scene = temporary_path(dir.file("s.cwscene"), gone);
  // Kept: writes of live processes (this test and a child), a folder, and names that only
  // resemble a temporary.
  const std::string ours = temporary_path(dir.file("other.cww"), ::getpid());
  const std::string childs = temporary_path(dir.file("w.cww"), alive);
  const std::string folder = temporary_path(dir.file("f"), gone);
  const std::vector<std::string> lookalikes = {dir.file("w.cww.tmp." + std::to_string(gone)),
                                               dir.file(".w.cww.cwtmp.x" + std::to_string(gone)),
                                               dir.file(".cwtmp." + std::to_string(gone)),
                                               dir.file(".w.cww.cwtmp.0"), dir.file(".w.cww.cwtmp.-1")};
  for (const std::string& f : {stale_world, stale_scene, ours, childs}) test::spit(f, {1, 2, 3});
  for (const std::string& f : lookalikes) test::spit(f, {1, 2, 3});
  fs::create_directory(folder);

  write_file_atomically(dir.file("w.cww"), "new");

  EXPECT_FALSE(fs::exists(stale_world));
  EXPECT_FALSE(fs::exists(stale_scene));
  for (const std::string& f : {ours, childs, folder}) EXPECT_TRUE(fs::exists(f)) << f;
  for (const std::string& f : lookalikes) EXPECT_TRUE(fs::exists(f)) << f;
  EXPECT_EQ(test::slurp(childs), (std::vector<uint8_t>{1, 2, 3}));  // not even truncated
  EXPECT_EQ(test::slurp(dir.file("w.cww")), (std::vector<uint8_t>{'n', 'e', 'w'}));
  stop(alive);
}

// The command line goes through the same writes: a killed build's temporary is gone after the
// next command that writes into its directory.
TEST(AtomicFile, NextCommandRemovesAKilledBuildsTemporary) {
  test::TempDir dir;
  const std::string scene = test::write_street_scene(dir, 4);
  const std::string stale = temporary_path(dir.file("w.cww"), exited_pid());
  fs::copy_file(scene, stale);
  const auto r = test::run_cellwalk("build " + scene + " -o " + dir.file("w.cww"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_FALSE(fs::exists(stale));
}

}  // namespace
}  // namespace cellwalk
