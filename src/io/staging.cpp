// Staging and locking of a run's output directory (see io/staging.hpp).
#include "io/staging.hpp"

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <set>
#include <vector>

#include <dirent.h>
#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include "freeflex/io/output.hpp"
#include "io/system_error.hpp"

namespace freeflex::staging {
namespace {

using io_detail::reason;

const char* const kManifest = ".freeflex-files";
const char* const kStagingPrefix = ".freeflex-staging-";
const char* const kLock = ".freeflex-lock";

/// Why `dir`, which exists but is no directory we can use, is refused (stat failed with
/// `err`, or found something else).
std::string not_a_directory(const std::string& dir, int err) {
  const std::string where = "output path '" + dir + "'";
  struct stat lst {};
  if (::lstat(dir.c_str(), &lst) == 0 && S_ISLNK(lst.st_mode)) {
    std::string target(4096, '\0');
    const ssize_t n = ::readlink(dir.c_str(), target.data(), target.size());
    target.resize(n > 0 ? static_cast<std::size_t>(n) : 0);
    const std::string link = where + " is a symbolic link to '" + target + "'";
    if (err == ELOOP) return where + " is a symbolic link that leads back to itself (a loop of links); give a directory";
    if (err == ENOENT) return link + ", which does not exist (a dangling link); create it or give a directory";
    if (err == 0) return link + ", which is not a directory";
    return link + " that cannot be followed: " + reason(err);
  }
  if (err != 0) return "cannot use " + where + ": " + reason(err);
  return where + " exists and is not a directory";
}

/// Creates DIR (and missing parents). Throws IoError with the reason.
void make_dirs(const std::string& dir) {
  std::string partial;
  std::size_t pos = 0;
  while (pos != std::string::npos) {
    pos = dir.find('/', pos + 1);
    partial = dir.substr(0, pos);
    if (partial.empty()) continue;
    if (::mkdir(partial.c_str(), 0755) != 0 && errno != EEXIST)
      throw IoError("cannot create output directory '" + partial + "': " + reason(errno));
  }
  struct stat st {};
  const int found = ::stat(dir.c_str(), &st);
  if (found == 0 && S_ISDIR(st.st_mode)) return;
  throw IoError(not_a_directory(dir, found == 0 ? 0 : errno));
}

/// Names of the regular files in `dir` (not recursive, symbolic links not followed);
/// empty if it cannot be read.
std::vector<std::string> list_files(const std::string& dir) {
  std::vector<std::string> names;
  DIR* d = ::opendir(dir.c_str());
  if (!d) return names;
  while (const dirent* e = ::readdir(d)) {
    const std::string name = e->d_name;
    if (name == "." || name == "..") continue;
    struct stat st {};
    if (::lstat((dir + "/" + name).c_str(), &st) == 0 && S_ISREG(st.st_mode)) names.push_back(name);
  }
  ::closedir(d);
  std::sort(names.begin(), names.end());
  return names;
}

/// Removes a staging directory (a flat directory of files); best effort. Anything else by
/// that name is unlinked: a link goes, never what it points to.
void remove_flat_dir(const std::string& dir) {
  struct stat st {};
  if (::lstat(dir.c_str(), &st) != 0) return;
  if (!S_ISDIR(st.st_mode)) {
    ::unlink(dir.c_str());
    return;
  }
  for (const auto& f : list_files(dir)) std::remove((dir + "/" + f).c_str());
  ::rmdir(dir.c_str());
}

std::vector<std::string> read_manifest(const std::string& dir) {
  std::vector<std::string> names;
  std::ifstream in(dir + "/" + kManifest);
  std::string line;
  while (std::getline(in, line))
    if (!line.empty() && line.find('/') == std::string::npos && line != "." && line != "..") names.push_back(line);
  return names;
}

/// Replaces DIR's manifest, going through a file in `staging` so that a run killed while
/// writing leaves nothing in DIR that no later run would remove.
void write_manifest(const std::string& staging, const std::string& dir, const std::set<std::string>& names) {
  std::string text;
  for (const auto& f : names) text += f + "\n";
  const std::string next = staging + "/" + kManifest;
  write_file_atomic(next, text);
  if (std::rename(next.c_str(), (dir + "/" + kManifest).c_str()) != 0)
    throw IoError("cannot write '" + dir + "/" + kManifest + "': " + reason(errno));
}

/// An exclusive lock on DIR; a second run into DIR fails at once. Returns the descriptor.
int lock(const std::string& dir) {
  const std::string path = dir + "/" + kLock;
  const int fd = ::open(path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC | O_NOFOLLOW, 0644);
  if (fd < 0) throw IoError("cannot open '" + path + "': " + reason(errno));
  if (::flock(fd, LOCK_EX | LOCK_NB) != 0) {
    const int err = errno;
    ::close(fd);
    if (err == EWOULDBLOCK)
      throw IoError("another freeflex run is writing into '" + dir +
                    "'; wait for it to finish or give this run another --out");
    throw IoError("cannot lock '" + path + "': " + reason(err));
  }
  return fd;
}

/// Staging directories left by runs that were killed. Only called with DIR locked, so no
/// other run is using one.
void remove_stale_staging(const std::string& dir) {
  DIR* d = ::opendir(dir.c_str());
  if (!d) return;
  std::vector<std::string> stale;
  while (const dirent* e = ::readdir(d)) {
    const std::string name = e->d_name;
    if (name.rfind(kStagingPrefix, 0) == 0) stale.push_back(dir + "/" + name);
  }
  ::closedir(d);
  for (const auto& s : stale) remove_flat_dir(s);
}

}  // namespace

StagedDirectory::StagedDirectory(std::string dir) : dir_(std::move(dir)) {
  make_dirs(dir_);
  lock_fd_ = lock(dir_);
  try {
    remove_stale_staging(dir_);
    staging_ = dir_ + "/" + kStagingPrefix + std::to_string(::getpid());
    if (::mkdir(staging_.c_str(), 0755) != 0)
      throw IoError("cannot create the staging directory of this run in '" + dir_ + "': " + reason(errno));
  } catch (...) {
    ::close(lock_fd_);
    throw;
  }
}

StagedDirectory::~StagedDirectory() {
  if (!committed_) discard();
  ::close(lock_fd_);  // releases the lock
}

void StagedDirectory::discard() { remove_flat_dir(staging_); }

std::size_t StagedDirectory::commit() {
  const std::vector<std::string> fresh = list_files(staging_);
  const std::set<std::string> keep(fresh.begin(), fresh.end());
  const std::vector<std::string> old = read_manifest(dir_);
  std::set<std::string> either(keep);
  either.insert(old.begin(), old.end());
  either.insert("summary.json");
  write_manifest(staging_, dir_, either);
  std::remove((dir_ + "/summary.json").c_str());  // until the new one is in, DIR claims nothing
  for (const auto& f : old)
    if (!keep.count(f)) std::remove((dir_ + "/" + f).c_str());
  auto move = [&](const std::string& name) {
    if (std::rename((staging_ + "/" + name).c_str(), (dir_ + "/" + name).c_str()) != 0)
      throw IoError("cannot move '" + name + "' into '" + dir_ + "': " + reason(errno) +
                    " (DIR now holds part of this run's files and no summary.json)");
  };
  for (const auto& f : fresh)
    if (f != "summary.json") move(f);
  write_manifest(staging_, dir_, keep);
  if (keep.count("summary.json")) move("summary.json");
  ::rmdir(staging_.c_str());
  committed_ = true;
  return fresh.size();
}

}  // namespace freeflex::staging
