// Atomic writes: every output (logs, reports, plots' data) is written to a
// temporary file in the destination folder and renamed into place, so a
// failure never leaves a half-written file behind (brief: Standards).
#pragma once

#include <functional>
#include <string>
#include <string_view>

namespace coaxid {

// Writes `contents` to `path` atomically. Throws InputError naming the path if
// the folder does not exist or cannot be written.
void WriteFileAtomically(const std::string& path, const std::string& contents);

// The same for a file written piece by piece, so that it never has to be in
// memory whole (an hour of flight's measured-versus-model table is 0.5 GB of
// text): produce(emit) calls emit(text) as often as it likes. If produce
// throws, nothing is left behind and the exception propagates.
using EmitText = std::function<void(std::string_view)>;
void WriteFileAtomically(const std::string& path,
                         const std::function<void(const EmitText& emit)>& produce);

// A table built row by row and emitted in pieces of about 1 MB: append to
// `text`, call EndOfRow after each row; the destructor emits the rest.
class TextPieces {
 public:
  explicit TextPieces(const EmitText& emit) : emit_(emit) {}
  TextPieces(const TextPieces&) = delete;
  TextPieces& operator=(const TextPieces&) = delete;
  ~TextPieces() { emit_(text); }
  void EndOfRow() {
    if (text.size() < (1 << 20)) return;
    emit_(text);
    text.clear();
  }
  std::string text;

 private:
  const EmitText& emit_;
};

// Creates the folder and its parents; InputError naming it if impossible.
void MakeOutputFolder(const std::string& dir);

// Reads a whole file. Throws InputError naming the path if it cannot be read.
std::string ReadFile(const std::string& path);

// A file read in pieces (a log of an hour is 290 MB of text: parsed piece by
// piece it never sits in memory whole). Throws InputError naming the path
// if it cannot be opened or read, as ReadFile.
class FileReader {
 public:
  explicit FileReader(const std::string& path);
  ~FileReader();
  FileReader(const FileReader&) = delete;
  FileReader& operator=(const FileReader&) = delete;
  // Reads up to `room` bytes into `dest`; 0 at the end of the file.
  size_t Read(char* dest, size_t room);
  // The size when opened (0 for pipes): a hint, not a promise.
  size_t size_hint() const { return size_hint_; }

 private:
  std::string path_;
  int fd_ = -1;
  size_t size_hint_ = 0;
};

}  // namespace coaxid
