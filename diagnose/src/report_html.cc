// report.html: report.md rendered by cmark-gfm (CommonMark with GitHub's tables), each figure
// (`![alt](plots/STEM.png)`) replaced by plots/STEM.svg inlined, so the page is one file.
#include <cmark-gfm-core-extensions.h>
#include <cmark-gfm-extension_api.h>
#include <cmark-gfm.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <memory>
#include <regex>
#include <sstream>

#include "fralab/analyze/bode_plot.h"
#include "fralab/core/error.h"
#include "fralab/diagnose/report.h"

namespace fs = std::filesystem;

namespace fralab {

namespace {

std::string slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

std::string markdown_to_html(const std::string& md) {
  cmark_gfm_core_extensions_ensure_registered();
  std::unique_ptr<cmark_parser, void (*)(cmark_parser*)> parser(cmark_parser_new(CMARK_OPT_DEFAULT),
                                                                cmark_parser_free);
  if (cmark_syntax_extension* table = cmark_find_syntax_extension("table"))
    cmark_parser_attach_syntax_extension(parser.get(), table);
  cmark_parser_feed(parser.get(), md.data(), md.size());
  std::unique_ptr<cmark_node, void (*)(cmark_node*)> doc(cmark_parser_finish(parser.get()),
                                                         cmark_node_free);
  char* html = cmark_render_html(doc.get(), CMARK_OPT_DEFAULT,
                                 cmark_parser_get_syntax_extensions(parser.get()));
  std::string out(html ? html : "");
  std::free(html);
  return out;
}

std::string escape(const std::string& s) {
  std::string o;
  for (char c : s) {
    if (c == '&')
      o += "&amp;";
    else if (c == '<')
      o += "&lt;";
    else if (c == '>')
      o += "&gt;";
    else if (c == '"')
      o += "&quot;";
    else
      o += c;
  }
  return o;
}

}  // namespace

void write_report_html(const std::string& dir, const std::string& title) {
  const fs::path md = fs::path(dir) / "report.md";
  if (!fs::exists(md)) throw InputError(md.string() + ": no report to render");
  std::string body = markdown_to_html(slurp(md));
  // <img src="plots/STEM.png" alt="ALT" /> -> <figure><svg ...>...</svg><figcaption>ALT
  static const std::regex img(R"re(<img src="(plots/[^"]+)\.png" alt="([^"]*)" />)re");
  std::string out;
  auto begin = std::sregex_iterator(body.begin(), body.end(), img);
  size_t last = 0;
  int inlined = 0;
  for (auto it = begin; it != std::sregex_iterator(); ++it) {
    const auto& m = *it;
    out += body.substr(last, size_t(m.position()) - last);
    const fs::path svg = fs::path(dir) / (m[1].str() + ".svg");
    const std::string fig = inline_svg(svg.string());
    if (fig.empty()) {
      out += m.str();  // no SVG: the PNG stays referenced
    } else {
      out += "<figure>" + fig + "<figcaption>" + m[2].str() + "</figcaption></figure>";
      ++inlined;
    }
    last = size_t(m.position() + m.length());
  }
  out += body.substr(last);
  std::ofstream html(fs::path(dir) / "report.html");
  html << "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n<title>"
       << escape(title)
       << "</title>\n<style>\nbody{font-family:sans-serif;max-width:1000px;margin:2em "
          "auto;padding:0 1em;line-height:1.4}\ntable{border-collapse:collapse}\ntd,th{border:"
          "1px solid #bbb;padding:2px 8px;text-align:right}\nfigure{margin:1em 0}\nfigure "
          "svg{max-width:100%;height:auto}\nfigcaption{color:#555}\n</style>\n</head>\n<body>\n"
       << out << "</body>\n</html>\n";
  if (!html) throw InputError((fs::path(dir) / "report.html").string() + ": cannot be written");
}

}  // namespace fralab
