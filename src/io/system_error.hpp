#pragma once
// errno in words for the messages of io/ (IoError). Private to src/.
#include <cerrno>
#include <cstring>
#include <string>

namespace freeflex::io_detail {

/// strerror(err); a full file system may be out of inodes rather than bytes, so ENOSPC says so.
inline std::string reason(int err) {
  std::string why = std::strerror(err);
  if (err == ENOSPC) why += " (the file system is full or has no free inodes)";
  return why;
}

}  // namespace freeflex::io_detail
