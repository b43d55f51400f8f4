// Runs the built `coaxid` program (COAXID_BINARY, set by tests/CMakeLists.txt)
// for the CLI tests: exit status and everything it printed.
#pragma once

#include <sys/wait.h>

#include <cstdio>
#include <string>

namespace coaxid {

struct RunResult {
  int status;          // exit status, -1 if it did not exit normally
  std::string output;  // stdout + stderr
};

inline RunResult RunCoaxid(const std::string& args) {
  const std::string command = std::string(COAXID_BINARY) + " " + args + " 2>&1";
  FILE* pipe = popen(command.c_str(), "r");
  std::string output;
  char buffer[4096];
  while (size_t n = fread(buffer, 1, sizeof buffer, pipe)) output.append(buffer, n);
  const int status = pclose(pipe);
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, output};
}

inline bool Contains(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

}  // namespace coaxid
