// Escaping text for HTML and XML (SVG) markup, shared by the HTML report and the SVG plots.
#pragma once

#include <string>

namespace qm3d::report {

/// `s` with & < > " ' replaced by character references: safe as element text and inside quoted
/// attribute values, in HTML and in XML.
inline std::string markup_escaped(const std::string& s) {
  std::string out;
  out.reserve(s.size());
  for (char c : s) {
    switch (c) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      case '\'': out += "&#39;"; break;
      default: out += c;
    }
  }
  return out;
}

}  // namespace qm3d::report
