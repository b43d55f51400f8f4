// The Markdown the reports write (headings, paragraphs, pipe tables, "- "
// lists, images, links, **bold**, `code`) as one self-contained HTML page:
// the styles inline, images by the relative paths the Markdown gives, so the
// page opens in a browser from the folder it sits in. Anything else is kept
// as paragraph text (HTML-escaped), never dropped.
#pragma once

#include <string>

namespace coaxid {

// A complete HTML document; title goes in <title>.
std::string MarkdownToHtml(const std::string& markdown, const std::string& title);

}  // namespace coaxid
