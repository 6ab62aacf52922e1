#pragma once
// Staging and locking of a run's output directory (POSIX): one run at a time writes into
// DIR, into a hidden staging directory, and moves its files in only when it has finished,
// so DIR never mixes two runs. Private to src/.
//
// A run writes into DIR/.freeflex-staging-<pid>. The manifest DIR/.freeflex-files lists
// the files a run may have left in DIR; the next run removes them first, so no stale
// result outlives the run that replaced it. summary.json goes last. The lock is held on
// DIR/.freeflex-lock from start to end.
#include <cstddef>
#include <string>

namespace freeflex::staging {

class StagedDirectory {
 public:
  /// Creates DIR (and missing parents), locks it, clears staging directories that killed
  /// runs left and creates this run's. Throws IoError (another run holds DIR, DIR is not
  /// a directory, a file system error) with the reason.
  explicit StagedDirectory(std::string dir);
  /// Removes the staging directory unless commit() moved its files in.
  ~StagedDirectory();
  StagedDirectory(const StagedDirectory&) = delete;
  StagedDirectory& operator=(const StagedDirectory&) = delete;

  const std::string& dir() const { return dir_; }
  const std::string& staging() const { return staging_; }

  /// Moves every staged file into DIR, replacing the previous run's files (summary.json
  /// last); returns how many it moved. Whenever it stops (killed, or a move fails: then
  /// IoError), the manifest lists every file of either run that DIR may hold, so that the
  /// next run clears them all.
  std::size_t commit();
  /// Removes the staging directory and what it holds (best effort).
  void discard();

 private:
  std::string dir_, staging_;
  int lock_fd_ = -1;
  bool committed_ = false;
};

}  // namespace freeflex::staging
