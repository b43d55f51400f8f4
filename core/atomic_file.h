// Atomic writes: every output (logs, reports, plots' data) is written to a
// temporary file in the destination folder and renamed into place, so a
// failure never leaves a half-written file behind (brief: Standards).
#pragma once

#include <string>

namespace coaxid {

// Writes `contents` to `path` atomically. Throws InputError naming the path if
// the folder does not exist or cannot be written.
void WriteFileAtomically(const std::string& path, const std::string& contents);

// Creates the folder and its parents; InputError naming it if impossible.
void MakeOutputFolder(const std::string& dir);

// Reads a whole file. Throws InputError naming the path if it cannot be read.
std::string ReadFile(const std::string& path);

}  // namespace coaxid
