#include "experiments/reports/markdown_html.h"

#include <sstream>
#include <vector>

namespace coaxid {
namespace {

constexpr const char* kStyle =
    "body{font-family:system-ui,-apple-system,Segoe UI,Helvetica,Arial,sans-serif;"
    "max-width:1250px;margin:2em auto;padding:0 1em;line-height:1.45;color:#222}"
    "h1{border-bottom:2px solid #ccc}h2{border-bottom:1px solid #ddd;margin-top:2em}"
    "table{border-collapse:collapse;margin:0.8em 0;font-size:0.92em}"
    "th,td{border:1px solid #ccc;padding:3px 8px;text-align:left;vertical-align:top}"
    "th{background:#f0f0f0}tr:nth-child(even) td{background:#fafafa}"
    "code{background:#f3f3f3;padding:0 3px;border-radius:3px}"
    "img{max-width:100%;border:1px solid #ddd}figure{margin:1em 0}"
    "figcaption{font-size:0.85em;color:#555}";

std::string Escape(const std::string& text) {
  std::string out;
  for (char c : text) {
    if (c == '&') {
      out += "&amp;";
    } else if (c == '<') {
      out += "&lt;";
    } else if (c == '>') {
      out += "&gt;";
    } else if (c == '"') {
      out += "&quot;";
    } else {
      out += c;
    }
  }
  return out;
}

// Inline markup of one (unescaped) line: images, links, **bold**, `code`.
std::string Inline(const std::string& text) {
  std::string out;
  size_t i = 0;
  while (i < text.size()) {
    if (text[i] == '`') {
      const size_t end = text.find('`', i + 1);
      if (end != std::string::npos) {
        out += "<code>" + Escape(text.substr(i + 1, end - i - 1)) + "</code>";
        i = end + 1;
        continue;
      }
    }
    if (text.compare(i, 2, "**") == 0) {
      const size_t end = text.find("**", i + 2);
      if (end != std::string::npos) {
        out += "<strong>" + Inline(text.substr(i + 2, end - i - 2)) + "</strong>";
        i = end + 2;
        continue;
      }
    }
    const bool image = text.compare(i, 2, "![") == 0;
    if (image || text[i] == '[') {
      const size_t open = i + (image ? 2 : 1);
      const size_t close = text.find("](", open);
      const size_t end = close == std::string::npos ? close : text.find(')', close + 2);
      if (end != std::string::npos) {
        const std::string label = text.substr(open, close - open);
        const std::string target = Escape(text.substr(close + 2, end - close - 2));
        out += image ? "<img src=\"" + target + "\" alt=\"" + Escape(label) + "\">"
                     : "<a href=\"" + target + "\">" + Inline(label) + "</a>";
        i = end + 1;
        continue;
      }
    }
    out += Escape(std::string(1, text[i]));
    ++i;
  }
  return out;
}

std::vector<std::string> Cells(const std::string& line) {
  std::vector<std::string> cells;
  std::string s = line;
  while (!s.empty() && (s.back() == ' ' || s.back() == '\r')) s.pop_back();
  if (!s.empty() && s.front() == '|') s.erase(0, 1);
  if (!s.empty() && s.back() == '|') s.pop_back();
  std::string cell;
  bool in_code = false;
  for (char c : s) {
    if (c == '`') in_code = !in_code;
    if (c == '|' && !in_code) {
      cells.push_back(cell);
      cell.clear();
    } else {
      cell += c;
    }
  }
  cells.push_back(cell);
  for (std::string& c : cells) {
    const size_t a = c.find_first_not_of(' ');
    const size_t b = c.find_last_not_of(' ');
    c = a == std::string::npos ? "" : c.substr(a, b - a + 1);
  }
  return cells;
}

bool IsSeparator(const std::string& line) {
  return line.rfind("|", 0) == 0 && line.find("---") != std::string::npos &&
         line.find_first_not_of("|-: ") == std::string::npos;
}

}  // namespace

std::string MarkdownToHtml(const std::string& markdown, const std::string& title) {
  std::vector<std::string> lines;
  std::istringstream in(markdown);
  for (std::string line; std::getline(in, line);) lines.push_back(line);

  std::ostringstream o;
  o << "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n<title>"
    << Escape(title) << "</title>\n<style>" << kStyle << "</style>\n</head>\n<body>\n";
  std::string paragraph;
  auto flush = [&]() {
    if (!paragraph.empty()) o << "<p>" << Inline(paragraph) << "</p>\n";
    paragraph.clear();
  };
  for (size_t i = 0; i < lines.size(); ++i) {
    const std::string& line = lines[i];
    if (line.find_first_not_of(" \r") == std::string::npos) {
      flush();
      continue;
    }
    size_t level = 0;
    while (level < line.size() && line[level] == '#') ++level;
    if (level >= 1 && level <= 6 && level < line.size() && line[level] == ' ') {
      flush();
      o << "<h" << level << ">" << Inline(line.substr(level + 1)) << "</h" << level << ">\n";
      continue;
    }
    if (line.rfind("|", 0) == 0 && i + 1 < lines.size() && IsSeparator(lines[i + 1])) {
      flush();
      o << "<table>\n<tr>";
      for (const std::string& c : Cells(line)) o << "<th>" << Inline(c) << "</th>";
      o << "</tr>\n";
      for (i += 2; i < lines.size() && lines[i].rfind("|", 0) == 0; ++i) {
        o << "<tr>";
        for (const std::string& c : Cells(lines[i])) o << "<td>" << Inline(c) << "</td>";
        o << "</tr>\n";
      }
      --i;
      o << "</table>\n";
      continue;
    }
    if (line.rfind("- ", 0) == 0) {
      flush();
      o << "<ul>\n";
      for (; i < lines.size() && lines[i].rfind("- ", 0) == 0; ++i) {
        o << "<li>" << Inline(lines[i].substr(2)) << "</li>\n";
      }
      --i;
      o << "</ul>\n";
      continue;
    }
    if (line.rfind("![", 0) == 0 && line.back() == ')' && line.find("](") != std::string::npos) {
      flush();
      const std::string caption = line.substr(2, line.find("](") - 2);
      o << "<figure>" << Inline(line) << "<figcaption>" << Inline(caption)
        << "</figcaption></figure>\n";
      continue;
    }
    paragraph += (paragraph.empty() ? "" : " ") + line;
  }
  flush();
  o << "</body>\n</html>\n";
  return o.str();
}

}  // namespace coaxid
