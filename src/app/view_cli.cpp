// `overtake view FILE`: the replay viewer in the browser, served or as one file.

#include "overtake/app/cli.hpp"
#include "overtake/app/interrupt.hpp"
#include "overtake/run/drive.hpp"
#include "overtake/run/pages.hpp"

namespace overtake::app {

using run::run_view;
using run::ViewOptions;

Subcommand register_view(CLI::App& app) {
  struct State {
    ViewOptions opts;
    std::string replay, html;
  };
  auto st = std::make_shared<State>();
  auto* cmd = app.add_subcommand(
      "view",
      "Watch a replay (from --record) in the browser: serves the viewer page at\n"
      "http://127.0.0.1:8080/ until Ctrl-C, or writes it as one self-contained file (--html).");
  cmd->add_option("replay", st->replay, "The replay file (.otr)")->required();
  cmd->add_option("--port", st->opts.port, "TCP port to serve the page on (0: any free port)")
      ->capture_default_str();
  cmd->add_option("--host", st->opts.host,
                  "Address to serve on (loopback by default: the page is for this machine;\n"
                  "0.0.0.0 shares it with the network)")
      ->capture_default_str();
  cmd->add_option("--html", st->html,
                  "Write one self-contained HTML file (the page with the replay inside; it opens\n"
                  "from disk and can be shared) and exit, instead of serving");
  cmd->add_flag("--partial", st->opts.partial,
                "Show a replay that is cut short or damaged (e.g. the FILE.partial of a killed\n"
                "run): the page shows the records before the fault, with a warning");
  cmd->add_flag("--quiet,-q", st->opts.quiet, "No messages but errors");
  return {cmd, [st] {
            ViewOptions o = st->opts;
            o.replay = st->replay;
            if (!st->html.empty()) o.html = st->html;
            if (o.html) return run_view(o, InterruptScope::flag());
            const InterruptScope interrupt;
            return run_view(o, InterruptScope::flag());
          }};
}

}  // namespace overtake::app
