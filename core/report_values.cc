#include "core/report_values.h"

#include <charconv>
#include <cmath>
#include <cstdio>
#include <limits>

namespace coaxid {

double JsonNumber(const nlohmann::json& object, const std::string& key) {
  if (!object.is_object() || !object.contains(key) || !object[key].is_number()) {
    return std::numeric_limits<double>::quiet_NaN();
  }
  return object[key].get<double>();
}

std::string Joined(const std::vector<std::string>& parts, const char* separator) {
  std::string out;
  for (const std::string& p : parts) out += (out.empty() ? "" : separator) + p;
  return out;
}

std::string NumberText(double v, const char* format) {
  if (!std::isfinite(v)) return "-";
  char text[64];
  std::snprintf(text, sizeof text, format, v);
  return text;
}

char* WriteSignificant(char* out, double v, int digits) {
  return std::to_chars(out, out + 32, v, std::chars_format::general, digits).ptr;
}

std::string Significant(double v, int digits) {
  char text[32];
  return std::string(text, WriteSignificant(text, v, digits));
}

}  // namespace coaxid
