// Numbers in and out of the JSON reports: read one (NaN when it is missing or
// null, as reports write a NaN) and write one into a Markdown table ("-" when
// it is not finite).
#pragma once

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace coaxid {

// object[key] as a number; NaN when object is not an object, lacks key, or
// holds something else there.
double JsonNumber(const nlohmann::json& object, const std::string& key);

// The parts one after another, `separator` between them ("a, b, c").
std::string Joined(const std::vector<std::string>& parts, const char* separator = ", ");

// v printed with the printf format; "-" when v is NaN or infinite.
std::string NumberText(double v, const char* format = "%.4g");

// v with `digits` significant digits: the text printf's "%.<digits>g" gives (std::to_chars in
// general format, which the standard defines that way), written at `out`, which must hold 32
// characters; returns the end of the text. Tables of long logs are written with it: snprintf
// took 12 % of an EKF run on a 5-minute log.
char* WriteSignificant(char* out, double v, int digits);
std::string Significant(double v, int digits);

}  // namespace coaxid
