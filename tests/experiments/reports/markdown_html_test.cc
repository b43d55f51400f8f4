// The reports' Markdown as one self-contained HTML page
// (experiments/reports/markdown_html.h).
#include "experiments/reports/markdown_html.h"

#include <gtest/gtest.h>

#include <string>

#include "tests/run_coaxid.h"

namespace coaxid {
namespace {

TEST(MarkdownToHtml, RendersTheReportsMarkdownAsOnePage) {
  const std::string html = MarkdownToHtml(
      "# Title <1>\n\nSome **bold** and `code` text\ncontinued.\n\n"
      "| a | b |\n|---|---|\n| 1 | x < y |\n\n- one\n- [two](t.md)\n\n![a plot](plots/p.png)\n",
      "T");
  EXPECT_TRUE(Contains(html, "<!DOCTYPE html>"));
  EXPECT_TRUE(Contains(html, "<title>T</title>"));
  EXPECT_TRUE(Contains(html, "<h1>Title &lt;1&gt;</h1>"));
  EXPECT_TRUE(Contains(html,
                       "<p>Some <strong>bold</strong> and <code>code</code> text "
                       "continued.</p>"));
  EXPECT_TRUE(Contains(html, "<tr><th>a</th><th>b</th></tr>"));
  EXPECT_TRUE(Contains(html, "<tr><td>1</td><td>x &lt; y</td></tr>"));
  EXPECT_TRUE(Contains(html, "<li><a href=\"t.md\">two</a></li>"));
  EXPECT_TRUE(Contains(html, "<img src=\"plots/p.png\" alt=\"a plot\">"));
  EXPECT_FALSE(Contains(html, "|---|"));
  EXPECT_FALSE(Contains(html, "<script"));  // self-contained, nothing fetched
}

}  // namespace
}  // namespace coaxid
