#include "core/atomic_file.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <string>
#include <vector>

#include "core/errors.h"

namespace coaxid {
namespace {

[[noreturn]] void Fail(const std::string& path, const char* what, int error) {
  throw InputError(path + ": " + what + ": " + std::strerror(error));
}

// Writes all of [data, data + size), retrying short writes and EINTR. Returns errno or 0.
int WriteAll(int fd, const char* data, size_t size) {
  while (size > 0) {
    const ssize_t n = ::write(fd, data, size);
    if (n < 0) {
      if (errno == EINTR) continue;
      return errno;
    }
    data += n;
    size -= static_cast<size_t>(n);
  }
  return 0;
}

}  // namespace

void WriteFileAtomically(const std::string& path, const std::string& contents) {
  WriteFileAtomically(path, [&](const EmitText& emit) { emit(contents); });
}

void WriteFileAtomically(const std::string& path,
                         const std::function<void(const EmitText& emit)>& produce) {
  // The temporary file lives in the destination folder so that rename() is atomic
  // (same file system) and a crash leaves at most a stray *.tmp.* file, never a
  // truncated target.
  std::string tmp = path + ".tmp.XXXXXX";
  std::vector<char> tmp_buffer(tmp.begin(), tmp.end());
  tmp_buffer.push_back('\0');
  const int fd = ::mkstemp(tmp_buffer.data());
  if (fd < 0) Fail(path, "cannot create a temporary file to write", errno);
  tmp.assign(tmp_buffer.data());

  auto fail_and_clean = [&](const char* what, int error) {
    ::unlink(tmp.c_str());
    Fail(path, what, error);
  };

  // mkstemp makes the file 0600; give the result the mode of the file it
  // replaces, or the usual 0644 for a new file, so outputs stay readable by others.
  struct stat existing;
  const mode_t mode = ::stat(path.c_str(), &existing) == 0 ? (existing.st_mode & 07777) : 0644;
  if (::fchmod(fd, mode) != 0) {
    const int error = errno;
    ::close(fd);
    fail_and_clean("cannot set permissions of the temporary file", error);
  }
  int write_error = 0;
  try {
    produce([&](std::string_view text) {
      if (write_error == 0) write_error = WriteAll(fd, text.data(), text.size());
    });
  } catch (...) {
    ::close(fd);
    ::unlink(tmp.c_str());
    throw;
  }
  if (write_error != 0) {
    ::close(fd);
    fail_and_clean("cannot write", write_error);
  }
  // close() can report a deferred write error (NFS, full disk); check it.
  if (::close(fd) != 0) fail_and_clean("cannot write", errno);
  if (::rename(tmp.c_str(), path.c_str()) != 0) fail_and_clean("cannot rename into place", errno);
}

void MakeOutputFolder(const std::string& dir) {
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec || !std::filesystem::is_directory(dir)) {
    throw InputError("cannot create output folder '" + dir + "': " + ec.message());
  }
}

FileReader::FileReader(const std::string& path) : path_(path) {
  fd_ = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd_ < 0) Fail(path, "cannot open for reading", errno);
  struct stat info;
  if (::fstat(fd_, &info) != 0) {
    const int error = errno;
    ::close(fd_);
    Fail(path, "cannot read", error);
  }
  if (S_ISDIR(info.st_mode)) {
    ::close(fd_);
    Fail(path, "cannot read", EISDIR);
  }
  size_hint_ = info.st_size > 0 ? static_cast<size_t>(info.st_size) : 0;
}

FileReader::~FileReader() { ::close(fd_); }

size_t FileReader::Read(char* dest, size_t room) {
  while (true) {
    const ssize_t n = ::read(fd_, dest, room);
    if (n >= 0) return static_cast<size_t>(n);
    if (errno != EINTR) Fail(path_, "cannot read", errno);
  }
}

std::string ReadFile(const std::string& path) {
  FileReader file(path);
  // One allocation of the right size and one read for regular files; the loop
  // also copes with pipes and files that grow while being read.
  std::string contents(file.size_hint(), '\0');
  size_t used = 0;
  char chunk[1 << 16];
  while (true) {
    char* dest = used < contents.size() ? &contents[used] : chunk;
    const size_t room = used < contents.size() ? contents.size() - used : sizeof(chunk);
    const size_t n = file.Read(dest, room);
    if (n == 0) break;
    if (dest == chunk) {
      contents.resize(used);
      contents.append(chunk, n);
    }
    used += n;
  }
  contents.resize(used);
  return contents;
}

}  // namespace coaxid
