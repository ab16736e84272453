// Replays at the command line and in the browser: recorded drives, `view --html`, the view
// server (HTTP and the live websocket), `bench --record-worst` and the bench report page.
// The pages are fixtures with the real pages' placeholders, so these tests do not depend on
// the web build; the tests of the shipped pages skip in a build made without them
// (OVERTAKE_WEB=OFF), where the commands that need them are shown to say so.

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <zlib.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <thread>
#include <vector>

#include <sys/stat.h>

#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#include <boost/asio/connect.hpp>
#include <boost/asio/io_context.hpp>
#include <boost/asio/ip/tcp.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>
#include <boost/beast/websocket.hpp>
#pragma GCC diagnostic pop

#include "overtake/app/cli.hpp"
#include "overtake/base/build_info.hpp"
#include "overtake/base/errors.hpp"
#include "overtake/base/io.hpp"
#include "overtake/batch/bench.hpp"
#include "overtake/batch/bench_page.hpp"
#include "overtake/core/base64.hpp"
#include "overtake/planner/policy.hpp"
#include "overtake/replay/replay.hpp"
#include "overtake/run/config.hpp"
#include "overtake/run/drive.hpp"
#include "overtake/run/pages.hpp"
#include "overtake/run/report.hpp"
#include "overtake/run/resources.hpp"
#include "overtake/sim/world.hpp"
#include "overtake/view/page.hpp"
#include "overtake/view/server.hpp"
#include "zlib_support.hpp"

namespace overtake::app {

using base::overtake_version;
using base::read_file;
using base::UsageError;
using base::write_file_atomic;
using batch::bench_replay_name;
using batch::BenchOutcome;
using batch::BenchSpec;
using batch::load_bench_runs;
using batch::merge_bench;
using batch::run_bench;
using batch::write_bench_report;
using run::Config;
using run::drive;
using run::DriveOptions;
using run::DriveResult;
using run::embedded_page;
using run::kReportPageName;
using run::kViewerPageName;
using run::load_config;
using run::load_track;
using run::replay_header_for;
using run::replay_report_json;
using run::report_to_json;
using run::RunProvenance;
using run::write_viewer_html;
namespace {

using nlohmann::json;
using ::testing::HasSubstr;
using ::testing::Not;
namespace fs = std::filesystem;
namespace net = boost::asio;
namespace beast = boost::beast;
namespace http = beast::http;
namespace websocket = beast::websocket;
using tcp = net::ip::tcp;

// The viewer page's placeholders as web/dist/viewer.html has them; its code mentions them too.
constexpr const char* kViewerFixture = R"(<!doctype html>
<html><head><title>fixture</title>
<script>
  // The page's code may mention the element and the placeholder: these are left alone.
  const el = document.querySelector('script[id="overtake-config"]');
  if (el.textContent.trim() === "__OVERTAKE_CONFIG__") console.log("not filled");
</script></head>
<body>
<script id="overtake-config" type="application/json">__OVERTAKE_CONFIG__</script>
<script id="overtake-data" type="application/octet-stream">
__OVERTAKE_DATA__
</script>
</body></html>
)";

constexpr const char* kReportFixture = R"(<!doctype html>
<html><body>
<script id="overtake-bench" type="application/json">__OVERTAKE_BENCH__</script>
</body></html>
)";

// The text content of the <script> element with this id.
std::string element_text(const std::string& page, const std::string& id) {
  const auto at = page.find("<script id=\"" + id + "\"");
  if (at == std::string::npos) return "<missing>";
  const auto open = page.find('>', at) + 1;
  return page.substr(open, page.find("</script>", open) - open);
}

std::string bytes_of(const fs::path& p) {
  return read_file(p);
}

int cli(std::vector<std::string> args) {
  args.insert(args.begin(), "overtake");
  std::vector<const char*> argv;
  for (const auto& a : args) argv.push_back(a.c_str());
  return run_cli(static_cast<int>(argv.size()), argv.data());
}

// Whether this build was configured with the web pages (OVERTAKE_WEB); when it was, they must
// be there.
constexpr bool has_embedded_pages() {
  return OVERTAKE_WEB_PAGES != 0;
}
constexpr const char* kNoPages = "this build was made without the web pages (OVERTAKE_WEB=OFF)";

class ViewerTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("overtake_viewer_test_" +
            std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  // A short recorded drive.
  fs::path recorded(const std::string& name, double minutes = 0.2, std::uint64_t seed = 3) {
    DriveOptions o;
    o.minutes = minutes;
    o.seed = seed;
    o.record = dir_ / name;
    (void)drive(o);
    return *o.record;
  }

  fs::path dir_;
};

// ---- recorded drives ----------------------------------------------------------------------

TEST_F(ViewerTest, ARecordedScenarioWithACollisionHasItsIncidentRecord) {
  DriveOptions o;
  o.policy = "walkthrough";  // does not brake hard enough for this scenario
  o.scenario = fs::path(OVERTAKE_SOURCE_DIR) / "tests/scenarios/hard_brake_ahead.json";
  o.minutes_from_scenario = true;
  o.record = dir_ / "brake.otr";
  const DriveResult r = drive(o);
  ASSERT_GT(r.report.incident_counts[static_cast<std::size_t>(sim::IncidentType::collision)], 0);

  const replay::Replay replay = replay::read_replay(*o.record);
  ASSERT_EQ(replay.incidents.size(), r.report.incidents.size());
  bool collision = false;
  for (std::size_t i = 0; i < replay.incidents.size(); ++i) {
    const sim::Incident& want = r.report.incidents[i];
    EXPECT_EQ(replay.incidents[i].type, static_cast<int>(want.type));
    EXPECT_EQ(replay.incidents[i].step, std::lround(want.t_s / 0.02));
    EXPECT_EQ(replay.header.incident_types[static_cast<std::size_t>(replay.incidents[i].type)],
              sim::to_string(want.type));
    if (want.type == sim::IncidentType::collision) {
      collision = true;
      EXPECT_FLOAT_EQ(static_cast<float>(replay.incidents[i].value),
                      static_cast<float>(want.value));
      // Its class, as the report has it: the walkthrough drove into the braking car.
      ASSERT_TRUE(replay.incidents[i].collision.has_value());
      EXPECT_EQ(replay.incidents[i].collision, want.collision);
      EXPECT_EQ(replay.incidents[i].collision->kind, sim::CollisionKind::ego_hit_car_ahead);
      EXPECT_TRUE(replay.incidents[i].collision->at_fault);
    } else {
      EXPECT_FALSE(replay.incidents[i].collision.has_value());
    }
  }
  EXPECT_TRUE(collision);
  // The end record is the report without its timing.
  json report = report_to_json(r.report, r.provenance);
  report.erase("timing");
  EXPECT_EQ(json::parse(replay.end_json), report);
  EXPECT_EQ(replay.header.provenance.traffic, "scripted");
  EXPECT_EQ(replay.header.provenance.policy, "walkthrough");
  EXPECT_EQ(replay.frames.back().step, std::lround(r.report.duration_s / 0.02));
  EXPECT_EQ(static_cast<long>(replay.paths.size()), r.report.planner_cycles);
}

TEST_F(ViewerTest, SameSeedGivesAByteIdenticalReplay) {
  const std::string a = bytes_of(recorded("a.otr", 0.5, 3));
  const std::string b = bytes_of(recorded("b.otr", 0.5, 3));
  const std::string c = bytes_of(recorded("c.otr", 0.5, 4));
  EXPECT_EQ(a, b);
  EXPECT_NE(a, c);
  const replay::Replay r = replay::parse_replay(a, "a.otr");
  EXPECT_EQ(r.header.provenance.seed, 3u);
  EXPECT_EQ(r.header.provenance.policy, "reference");
  EXPECT_EQ(r.header.provenance.track, "default");
  EXPECT_DOUBLE_EQ(r.header.provenance.duration_s, 30.0);
  EXPECT_EQ(r.header.provenance.overtake_version, overtake_version());
  EXPECT_EQ(r.frames.size(), 1501u);
}

TEST_F(ViewerTest, DriveRecordAtTheCommandLine) {
  const fs::path file = dir_ / "cli.otr";
  testing::internal::CaptureStdout();
  EXPECT_EQ(cli({"drive", "--minutes", "0.1", "--record", file.string(), "--quiet"}), 0);
  (void)testing::internal::GetCapturedStdout();
  EXPECT_EQ(replay::read_replay(file).frames.size(), 301u);

  testing::internal::CaptureStdout();
  testing::internal::CaptureStderr();
  EXPECT_EQ(cli({"drive", "--minutes", "0.1", "--record", (dir_ / "nope" / "x.otr").string()}), 1);
  (void)testing::internal::GetCapturedStdout();
  EXPECT_THAT(testing::internal::GetCapturedStderr(),
              HasSubstr("nope/x.otr.partial: cannot create"));

  testing::internal::CaptureStderr();
  EXPECT_EQ(cli({"drive", "--port", "9000"}), 2);  // --port needs --live
  EXPECT_THAT(testing::internal::GetCapturedStderr(), HasSubstr("--live"));
}

TEST_F(ViewerTest, APipeIsWrittenInPlaceNotReplaced) {
  // As /dev/null or /dev/stdout would be: a rename over them would replace the device.
  const fs::path fifo = dir_ / "pipe";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  for (int round = 0; round < 2; ++round) {
    std::string got;
    std::thread reader([&] {
      std::ifstream in(fifo, std::ios::binary);
      got.assign(std::istreambuf_iterator<char>(in), {});
    });
    if (round == 0) {
      write_file_atomic(fifo, "through the pipe");
    } else {
      DriveOptions o;
      o.minutes = 0.05;
      o.record = fifo;
      (void)drive(o);
    }
    reader.join();
    EXPECT_TRUE(fs::is_fifo(fifo));
    if (round == 0) {
      EXPECT_EQ(got, "through the pipe");
    } else {
      EXPECT_EQ(replay::parse_replay(got, "pipe").frames.size(), 151u);
    }
  }
  EXPECT_FALSE(fs::exists(dir_ / "pipe.partial"));
}

// ---- pages --------------------------------------------------------------------------------

TEST(ViewPage, Base64RoundTripsEverySizeOfTail) {
  for (const std::string& s :
       std::vector<std::string>{"", "a", "ab", "abc", "abcd", std::string("\0\xff\x80 z", 5)}) {
    const std::string e = core::base64_encode(s);
    EXPECT_EQ(e.size() % 4, 0u);
    EXPECT_EQ(core::base64_decode(e), s);
  }
  EXPECT_EQ(core::base64_encode("hello"), "aGVsbG8=");
  EXPECT_EQ(core::base64_decode("aGVs\nbG8="), "hello");
  EXPECT_EQ(core::base64_decode("aGVsbG8"), std::nullopt);
  EXPECT_EQ(core::base64_decode("a*Vs"), std::nullopt);
}

TEST(ViewPage, FillsOnlyTheElementAndEscapesScriptEnds) {
  const std::string page =
      view::fill_script_element(kViewerFixture, view::kConfigElementId, view::kConfigPlaceholder,
                                view::script_safe_json(R"({"a":"</script><b>"})"));
  EXPECT_EQ(element_text(page, "overtake-config"), R"({"a":"\u003c/script>\u003cb>"})");
  EXPECT_THAT(page, HasSubstr(R"(el.textContent.trim() === "__OVERTAKE_CONFIG__")"));
  EXPECT_EQ(json::parse(element_text(page, "overtake-config"))["a"], "</script><b>");
  // Filled twice, or the wrong page: a clear error.
  EXPECT_THROW(
      (void)view::fill_script_element(page, view::kConfigElementId, view::kConfigPlaceholder, "{}"),
      view::ViewError);
  try {
    (void)view::viewer_page(kReportFixture, view::ViewerSource::http);
    FAIL();
  } catch (const view::ViewError& e) {
    EXPECT_THAT(e.what(), HasSubstr("no <script id=\"overtake-config\"> element"));
  }
}

TEST_F(ViewerTest, ViewHtmlEmbedsTheReplayInThePage) {
  const fs::path replay = recorded("r.otr");
  const fs::path out = dir_ / "r.html";
  write_viewer_html(bytes_of(replay), out, kViewerFixture);
  const std::string page = read_file(out);
  EXPECT_EQ(json::parse(element_text(page, "overtake-config")),
            json::parse(R"({"source":"embedded"})"));
  EXPECT_EQ(core::base64_decode(element_text(page, "overtake-data")), bytes_of(replay));
  EXPECT_THAT(element_text(page, "overtake-data"), Not(HasSubstr("__OVERTAKE")));
}

TEST_F(ViewerTest, ViewAtTheCommandLine) {
  const fs::path replay = recorded("r.otr");
  // A damaged replay: exit 1, the file and the fault named, whatever the pages.
  std::string bytes = bytes_of(replay);
  const fs::path cut = dir_ / "cut.otr";
  write_file_atomic(cut, std::string_view(bytes).substr(0, bytes.size() * 9 / 10));  // in the body
  testing::internal::CaptureStderr();
  EXPECT_EQ(cli({"view", cut.string(), "--html", (dir_ / "x.html").string()}), 1);
  std::string err = testing::internal::GetCapturedStderr();
  EXPECT_THAT(err, HasSubstr(cut.string() + ": truncated"));
  EXPECT_THAT(err, HasSubstr("--partial"));
  EXPECT_FALSE(fs::exists(dir_ / "x.html"));
  testing::internal::CaptureStderr();
  EXPECT_EQ(cli({"view", (dir_ / "missing.otr").string()}), 1);
  EXPECT_THAT(testing::internal::GetCapturedStderr(), HasSubstr("missing.otr: cannot open"));
  testing::internal::CaptureStderr();
  EXPECT_EQ(cli({"view", replay.string(), "--port", "70000"}), 2);
  EXPECT_THAT(testing::internal::GetCapturedStderr(), HasSubstr("--port"));

  if (!has_embedded_pages()) GTEST_SKIP() << kNoPages;
  const fs::path out = dir_ / "r.html";
  testing::internal::CaptureStdout();
  EXPECT_EQ(cli({"view", replay.string(), "--html", out.string()}), 0);
  EXPECT_THAT(testing::internal::GetCapturedStdout(), HasSubstr("written: " + out.string()));
  const std::string page = read_file(out);
  EXPECT_EQ(json::parse(element_text(page, "overtake-config"))["source"], "embedded");
  EXPECT_EQ(core::base64_decode(element_text(page, "overtake-data")), bytes);
  // --partial: the cut file's page, with a warning.
  testing::internal::CaptureStdout();
  testing::internal::CaptureStderr();
  EXPECT_EQ(cli({"view", cut.string(), "--partial", "--html", out.string()}), 0);
  (void)testing::internal::GetCapturedStdout();
  EXPECT_THAT(testing::internal::GetCapturedStderr(), HasSubstr("warning: "));
}

// ---- the server ---------------------------------------------------------------------------

struct Got {
  unsigned status = 0;
  std::string type;
  std::string body;
  std::string length;
};

Got http_get(std::uint16_t port, const std::string& target, http::verb verb = http::verb::get) {
  net::io_context ioc;
  tcp::socket socket(ioc);
  socket.connect({net::ip::make_address("127.0.0.1"), port});
  http::request<http::empty_body> req{verb, target, 11};
  req.set(http::field::host, "127.0.0.1");
  req.keep_alive(false);
  http::write(socket, req);
  beast::flat_buffer buffer;
  http::response_parser<http::string_body> parser;
  parser.body_limit(std::size_t{1} << 30);
  parser.skip(verb == http::verb::head);
  http::read(socket, buffer, parser);
  const auto& res = parser.get();
  return {res.result_int(), std::string(res[http::field::content_type]), res.body(),
          std::string(res[http::field::content_length])};
}

TEST_F(ViewerTest, ViewHtmlNeverOverwritesTheReplayAndWritesToADevice) {
  const fs::path replay = recorded("r.otr");
  const std::string bytes = bytes_of(replay);
  testing::internal::CaptureStderr();
  EXPECT_EQ(cli({"view", replay.string(), "--html", replay.string()}), 2);
  EXPECT_THAT(testing::internal::GetCapturedStderr(), HasSubstr("is the replay itself"));
  EXPECT_EQ(bytes_of(replay), bytes);
  if (!has_embedded_pages()) GTEST_SKIP() << kNoPages;
  // /dev/null once failed with "cannot get file size".
  testing::internal::CaptureStdout();
  testing::internal::CaptureStderr();
  EXPECT_EQ(cli({"view", replay.string(), "--html", "/dev/null"}), 0);
  EXPECT_THAT(testing::internal::GetCapturedStdout(), HasSubstr("written: /dev/null"));
  EXPECT_EQ(testing::internal::GetCapturedStderr(), "");
}

// The shipped pages are in the binary with their placeholders; in a build made without them,
// every command that needs one fails before doing anything, and says why.
TEST_F(ViewerTest, ThePagesAreEmbeddedOrTheCommandsSayTheBuildHasNone) {
  if (has_embedded_pages()) {
    const std::string_view viewer = embedded_page(kViewerPageName);
    EXPECT_THAT(std::string(viewer), HasSubstr(std::string(view::kConfigPlaceholder)));
    EXPECT_THAT(std::string(viewer), HasSubstr(std::string(view::kDataPlaceholder)));
    EXPECT_THAT(std::string(embedded_page(kReportPageName)),
                HasSubstr(std::string(view::kBenchPlaceholder)));
    return;
  }
  EXPECT_FALSE(resources::embedded_file(kViewerPageName).has_value());
  EXPECT_FALSE(resources::embedded_file(kReportPageName).has_value());
  try {
    (void)embedded_page(kViewerPageName);
    ADD_FAILURE() << "expected a std::runtime_error";
  } catch (const std::runtime_error& e) {
    EXPECT_THAT(e.what(), HasSubstr("no viewer.html page"));
    EXPECT_THAT(e.what(), HasSubstr("OVERTAKE_WEB=OFF"));
  }
  const auto fails_saying_why = [](std::vector<std::string> args) {
    testing::internal::CaptureStdout();
    testing::internal::CaptureStderr();
    const int rc = cli(std::move(args));
    (void)testing::internal::GetCapturedStdout();
    const std::string err = testing::internal::GetCapturedStderr();
    EXPECT_EQ(rc, 1);
    EXPECT_THAT(err, HasSubstr("made without the web pages (OVERTAKE_WEB=OFF)"));
  };
  const fs::path replay = recorded("r.otr");
  fails_saying_why({"view", replay.string(), "--html", (dir_ / "r.html").string()});
  EXPECT_FALSE(fs::exists(dir_ / "r.html"));
  fails_saying_why({"view", replay.string(), "--port", "0"});
  fails_saying_why({"drive", "--minutes", "0.01", "--live", "--port", "0"});
  fails_saying_why({"bench", "--policies", "walkthrough", "--seeds", "1", "--minutes", "0.01",
                    "--out", (dir_ / "bench").string(), "--html", (dir_ / "report.html").string()});
  EXPECT_FALSE(fs::exists(dir_ / "bench" / "runs.jsonl"));  // refused before any run
  EXPECT_FALSE(fs::exists(dir_ / "report.html"));
}

TEST_F(ViewerTest, ServerAnswersThePageTheReplayAnd404) {
  const std::string replay = bytes_of(recorded("r.otr"));
  view::ViewContent content;
  content.page = view::viewer_page(kViewerFixture, view::ViewerSource::http);
  content.replay = std::make_shared<const std::string>(replay);
  view::ViewServer server(content, {"127.0.0.1", 0});
  ASSERT_NE(server.port(), 0);
  EXPECT_EQ(server.url(), "http://127.0.0.1:" + std::to_string(server.port()) + "/");

  const Got page = http_get(server.port(), "/");
  EXPECT_EQ(page.status, 200u);
  EXPECT_THAT(page.type, HasSubstr("text/html"));
  EXPECT_EQ(page.body, content.page);
  EXPECT_EQ(json::parse(element_text(page.body, "overtake-config")),
            json::parse(R"({"source":"http","url":"/replay.otr"})"));
  EXPECT_EQ(element_text(page.body, "overtake-data"), "");

  const Got otr = http_get(server.port(), "/replay.otr");
  EXPECT_EQ(otr.status, 200u);
  EXPECT_EQ(otr.type, "application/octet-stream");
  EXPECT_EQ(otr.body, replay);

  EXPECT_EQ(http_get(server.port(), "/other").status, 404u);
  // Nothing but the page and the replay is served: no path reaches a file.
  for (const char* target : {"/../../../../etc/passwd", "/%2e%2e/%2e%2e/etc/passwd",
                             "/replay.otr/../../x", "//etc/passwd"}) {
    EXPECT_EQ(http_get(server.port(), target).status, 404u) << target;
  }
  EXPECT_EQ(http_get(server.port(), "/live").status, 404u);  // no live feed here
  EXPECT_EQ(http_get(server.port(), "/", http::verb::post).status, 405u);
  const Got head = http_get(server.port(), "/replay.otr", http::verb::head);
  EXPECT_EQ(head.status, 200u);
  EXPECT_EQ(head.length, std::to_string(replay.size()));
  EXPECT_EQ(head.body, "");
}

// The routing the server does (and fuzz/view_request_fuzz.cpp calls): the query is dropped,
// and the replay and the live feed exist only when the content has them.
TEST(ViewRoute, NamesThePageTheReplayAndTheLiveFeed) {
  view::ViewContent none;
  view::ViewContent all;
  all.replay = std::make_shared<const std::string>("x");
  all.live = std::make_shared<const view::LiveFeed>("{}");
  using view::ViewResource;
  for (const view::ViewContent* c : {&none, &all}) {
    EXPECT_EQ(view::route_target("/", *c).resource, ViewResource::page);
    EXPECT_EQ(view::route_target("/index.html?x=1", *c).resource, ViewResource::page);
    EXPECT_EQ(view::route_target("/missing?q", *c).resource, ViewResource::none);
    EXPECT_EQ(view::route_target("/missing?q", *c).path, "/missing");
    EXPECT_EQ(view::route_target("", *c).resource, ViewResource::none);
  }
  EXPECT_EQ(view::route_target("/replay.otr", none).resource, ViewResource::none);
  EXPECT_EQ(view::route_target("/replay.otr?t=3", all).resource, ViewResource::replay);
  EXPECT_EQ(view::route_target("/live", none).resource, ViewResource::none);
  EXPECT_EQ(view::route_target("/live", all).resource, ViewResource::live);
  EXPECT_EQ(view::route_target("/live/", all).resource, ViewResource::none);
}

TEST_F(ViewerTest, APortInUseIsReportedClearly) {
  view::ViewServer first({"page", nullptr, nullptr}, {"127.0.0.1", 0});
  try {
    view::ViewServer second({"page", nullptr, nullptr}, {"127.0.0.1", first.port()});
    FAIL() << "expected a ViewError";
  } catch (const view::ViewError& e) {
    EXPECT_THAT(e.what(), HasSubstr("cannot listen on 127.0.0.1:" + std::to_string(first.port())));
    EXPECT_THAT(e.what(), HasSubstr("already in use"));
    EXPECT_THAT(e.what(), HasSubstr("--port"));
  }
  EXPECT_THROW(view::ViewServer({"page", nullptr, nullptr}, {"192.0.2.1", 0}), view::ViewError);
}

// Everything a websocket viewer of /live receives: the header text, then the binary records,
// until the server closes.
struct LiveReceived {
  std::string header;
  std::string records;
  bool closed_normally = false;
};

LiveReceived watch_live(std::uint16_t port) {
  net::io_context ioc;
  websocket::stream<tcp::socket> ws(ioc);
  ws.next_layer().connect({net::ip::make_address("127.0.0.1"), port});
  ws.handshake("127.0.0.1", "/live");
  LiveReceived out;
  beast::flat_buffer buffer;
  ws.read(buffer);
  EXPECT_TRUE(ws.got_text());
  out.header = beast::buffers_to_string(buffer.data());
  for (;;) {
    buffer.clear();
    beast::error_code ec;
    ws.read(buffer, ec);
    if (ec == websocket::error::closed) {
      out.closed_normally = ws.reason().code == websocket::close_code::normal;
      break;
    }
    if (ec) break;
    EXPECT_TRUE(ws.got_binary());
    out.records += beast::buffers_to_string(buffer.data());
  }
  return out;
}

std::string inflated(const std::string& body) {
  z_stream z{};
  EXPECT_EQ(inflateInit(&z), Z_OK);
  z.next_in = reinterpret_cast<Bytef*>(const_cast<char*>(body.data()));
  z.avail_in = static_cast<uInt>(body.size());
  std::string out;
  int rc = Z_OK;
  while (rc == Z_OK) {
    char chunk[1 << 16];
    z.next_out = reinterpret_cast<Bytef*>(chunk);
    z.avail_out = sizeof chunk;
    rc = inflate(&z, Z_NO_FLUSH);
    out.append(chunk, sizeof chunk - z.avail_out);
  }
  EXPECT_EQ(rc, Z_STREAM_END);
  inflateEnd(&z);
  return out;
}

TEST_F(ViewerTest, LiveViewStreamsTheSameRecordsAsTheReplay) {
  // One drive, watched by a replay writer and a live feed at once (not paced: a test).
  const Config config = load_config(std::nullopt);
  const auto track = load_track(std::nullopt);
  DriveOptions o;
  o.minutes = 0.2;
  RunProvenance p;
  p.policy = "reference";
  p.traffic = "faithful";
  p.map_path = "builtin:default";
  const replay::ReplayHeader header = replay_header_for(*track, config, p, o.minutes * 60.0);
  auto feed = std::make_shared<view::LiveFeed>(replay::replay_header_json(header));
  view::LiveRecorder live(*feed);
  replay::ReplayWriter writer(dir_ / "r.otr", header);
  sim::ObserverList both({&writer, &live});
  sim::World world(track->map, track->line, config.world, sim::TrafficProfile::faithful, 1);
  auto policy = planner::make_policy("reference", track->line, config.planner);
  sim::RunOptions run;
  run.duration_s = o.minutes * 60.0;
  run.observer = both.get();
  const sim::RunReport report = sim::run_drive(
      world, [&](const core::Telemetry& t) { return policy->plan(t); }, run);
  const std::string end = replay_report_json(report, p);
  writer.finish(end);

  view::ViewContent content;
  content.page = view::viewer_page(kViewerFixture, view::ViewerSource::live);
  content.live = feed;
  view::ViewServer server(content, {"127.0.0.1", 0});
  EXPECT_EQ(json::parse(element_text(http_get(server.port(), "/").body, "overtake-config")),
            json::parse(R"({"source":"live","url":"/live"})"));
  EXPECT_EQ(http_get(server.port(), "/replay.otr").status, 404u);

  // A viewer that joins before the end gets the records so far, then the rest as they come.
  std::string got_records;
  std::thread viewer([&] {
    const LiveReceived r = watch_live(server.port());
    EXPECT_EQ(r.header, replay::replay_header_json(header));
    EXPECT_TRUE(r.closed_normally);
    got_records = r.records;
  });
  std::this_thread::sleep_for(std::chrono::milliseconds(100));
  live.finish(end);
  viewer.join();
  // A late viewer (after the end) gets the whole run too.
  const LiveReceived late = watch_live(server.port());
  EXPECT_EQ(late.records, got_records);

  // The live records are the replay file's body, inflated: the same decoding works.
  const replay::Replay from_file = replay::read_replay(dir_ / "r.otr");
  const replay::Replay from_live = replay::parse_replay(
      replay::replay_preamble(header) + test::deflate_all(got_records), "live");
  EXPECT_EQ(from_live.frames.size(), from_file.frames.size());
  EXPECT_EQ(from_live.paths.size(), from_file.paths.size());
  EXPECT_EQ(from_live.end_json, from_file.end_json);
  const std::string file = bytes_of(dir_ / "r.otr");
  EXPECT_EQ(got_records, inflated(file.substr(replay::replay_preamble(header).size())));
}

// ---- bench --------------------------------------------------------------------------------

TEST_F(ViewerTest, BenchRecordsItsWorstRunsAndLinksThemFromTheReport) {
  BenchSpec spec;
  spec.policies = {"walkthrough", "seed001"};
  spec.traffic = {"faithful"};
  spec.seeds = {1, 2, 3};
  spec.minutes = 1.0;
  spec.jobs = 2;
  spec.out = dir_ / "bench";
  spec.record_worst = 2;
  const BenchOutcome o = run_bench(spec, nullptr, {});
  ASSERT_EQ(o.replays.size(), 2u);

  // The two runs with most incidents (ties: lower seed first), recorded as they ran.
  std::vector<json> runs = load_bench_runs(spec.out);
  const auto total = [](const json& r) {
    int n = 0;
    for (const auto& [k, v] : r["incident_counts"].items()) n += v.get<int>();
    return n;
  };
  std::stable_sort(runs.begin(), runs.end(), [&](const json& a, const json& b) {
    if (total(a) != total(b)) return total(a) > total(b);
    return a["config"]["seed"].get<int>() < b["config"]["seed"].get<int>();
  });
  for (std::size_t i = 0; i < 2; ++i) {
    const json& run = runs[i];
    const fs::path want = spec.out / "replays" /
                          bench_replay_name(run["config"]["policy"].get<std::string>(),
                                            run["config"]["traffic"].get<std::string>(),
                                            run["config"]["seed"].get<std::uint64_t>());
    EXPECT_EQ(o.replays[i], want);
    const replay::Replay r = replay::read_replay(want);
    json report = run;
    for (const char* k : {"timing", "provenance", "index"}) report.erase(k);
    EXPECT_EQ(json::parse(r.end_json), report) << want;
  }

  // The report: bench.json, every run with its replay link or null, the summary.
  const fs::path html = dir_ / "report.html";
  const auto pages = write_bench_report(spec.out, html, kReportFixture, kViewerFixture);
  ASSERT_EQ(pages.size(), 2u);
  const json object = json::parse(element_text(read_file(html), "overtake-bench"));
  EXPECT_EQ(object["policies"], json({"walkthrough", "seed001"}));
  ASSERT_EQ(object["runs"].size(), 6u);
  ASSERT_EQ(object["summary"].size(), 2u);
  int linked = 0;
  for (const json& r : object["runs"]) {
    if (r["replay"].is_null()) continue;
    ++linked;
    const fs::path page = dir_ / r["replay"].get<std::string>();
    EXPECT_TRUE(fs::exists(page)) << page;
    EXPECT_EQ(r["replay"].get<std::string>().rfind("bench/replays/", 0), 0u);
    fs::path otr = page;
    otr.replace_extension(".otr");
    EXPECT_EQ(core::base64_decode(element_text(read_file(page), "overtake-data")), bytes_of(otr));
  }
  EXPECT_EQ(linked, 2);
}

TEST_F(ViewerTest, BenchMergeJoinsTheShardsReplaysAndWritesTheReport) {
  // Two shards of one sweep, each recording its worst run.
  std::vector<fs::path> shards;
  for (int i = 1; i <= 2; ++i) {
    BenchSpec spec;
    spec.policies = {"walkthrough"};
    spec.traffic = {"faithful"};
    spec.seeds = {1, 2, 3, 4};
    spec.minutes = 0.2;
    spec.jobs = 2;
    spec.shard_index = i;
    spec.shard_count = 2;
    spec.record_worst = 1;
    spec.out = dir_ / ("shard-" + std::to_string(i));
    ASSERT_EQ(run_bench(spec, nullptr, {}).replays.size(), 1u);
    shards.push_back(spec.out);
  }
  // Merged: both replays copied into the joined folder, the report links each to its page.
  const fs::path out = dir_ / "merged";
  const BenchOutcome m = merge_bench(shards, out);
  EXPECT_EQ(m.runs_done, 4u);
  ASSERT_EQ(m.replays.size(), 2u);
  for (const fs::path& r : m.replays) {
    EXPECT_EQ(r.parent_path(), out / "replays");
    const fs::path a = shards[0] / "replays" / r.filename();
    const fs::path b = shards[1] / "replays" / r.filename();
    EXPECT_EQ(bytes_of(r), bytes_of(fs::exists(a) ? a : b)) << r;
  }
  const fs::path html = dir_ / "report.html";
  ASSERT_EQ(write_bench_report(out, html, kReportFixture, kViewerFixture).size(), 2u);
  const auto check_report = [&](const fs::path& page, const std::string& folder) {
    const json object = json::parse(element_text(read_file(page), "overtake-bench"));
    EXPECT_EQ(object["shard"], "1/1");
    EXPECT_EQ(object["runs"].size(), 4u);
    EXPECT_EQ(object["summary"].size(), 1u);
    int linked = 0;
    for (const json& r : object["runs"]) {
      if (r["replay"].is_null()) continue;
      ++linked;
      EXPECT_EQ(r["replay"].get<std::string>().rfind(folder + "/replays/", 0), 0u) << r["replay"];
      EXPECT_TRUE(fs::exists(page.parent_path() / r["replay"].get<std::string>())) << r["replay"];
    }
    EXPECT_EQ(linked, 2);
  };
  check_report(html, "merged");

  // Merging into one of the shards is refused: the shard stays as it was.
  const fs::path into = dir_ / "into";
  fs::copy(shards[0], into, fs::copy_options::recursive);
  const std::string runs_before = read_file(into / "runs.jsonl");
  EXPECT_THROW((void)merge_bench({into, shards[1]}, into), UsageError);
  EXPECT_EQ(read_file(into / "runs.jsonl"), runs_before);
  EXPECT_EQ(std::distance(fs::directory_iterator(into / "replays"), fs::directory_iterator{}), 1);

  // At the command line, with the shipped pages: `bench merge ... --html`.
  if (!has_embedded_pages()) GTEST_SKIP() << kNoPages;
  const fs::path html2 = dir_ / "cli-report.html";
  testing::internal::CaptureStdout();
  EXPECT_EQ(cli({"bench", "merge", shards[0].string(), shards[1].string(), "--out",
                 (dir_ / "joined").string(), "--html", html2.string()}),
            0);
  const std::string said = testing::internal::GetCapturedStdout();
  EXPECT_THAT(said, HasSubstr("merged 4 runs into"));
  EXPECT_THAT(said, HasSubstr("report: " + html2.string() + " (2 replay pages linked)"));
  check_report(html2, "joined");
}

}  // namespace
}  // namespace overtake::app
