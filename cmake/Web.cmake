# The web pages (web/): the replay viewer and the bench report, each built by esbuild into one
# self-contained HTML file, then embedded into the binary (see src/app/CMakeLists.txt).
#
# overtake_web_pages(OUT_VAR) adds the command that builds them into ${PROJECT_BINARY_DIR}/web
# and sets OUT_VAR to the list "viewer.html=<path>;report.html=<path>" for overtake_embed.
# Call it from the directory whose target embeds the pages.
#
# With OVERTAKE_WEB=OFF nothing here needs Node.js: no pages are built or embedded (OUT_VAR is
# empty), the web tests are not registered, and the commands that serve or write a page say
# that this build was made without them.

if(OVERTAKE_WEB)
  find_program(OVERTAKE_NODE NAMES node nodejs DOC "Node.js, to build the web pages")
  if(NOT OVERTAKE_NODE)
    message(FATAL_ERROR "Node.js (node) was not found; it builds the web pages in web/. "
                        "Run scripts/install-deps.sh, or configure with -DOVERTAKE_WEB=OFF "
                        "(the `noweb` preset) for a build without the pages")
  endif()
else()
  message(STATUS "OVERTAKE_WEB=OFF: the web pages are not built into this binary")
endif()

set(OVERTAKE_WEB_SOURCE_DIR "${PROJECT_SOURCE_DIR}/web")
set(OVERTAKE_WEB_BINARY_DIR "${PROJECT_BINARY_DIR}/web")

function(overtake_web_pages out_var)
  if(NOT OVERTAKE_WEB)
    set(${out_var} "" PARENT_SCOPE)
    return()
  endif()
  file(GLOB_RECURSE sources CONFIGURE_DEPENDS "${OVERTAKE_WEB_SOURCE_DIR}/src/*")
  set(viewer "${OVERTAKE_WEB_BINARY_DIR}/viewer.html")
  set(report "${OVERTAKE_WEB_BINARY_DIR}/report.html")
  add_custom_command(
    OUTPUT "${viewer}" "${report}"
    COMMAND "${OVERTAKE_NODE}" "${OVERTAKE_WEB_SOURCE_DIR}/build.mjs" --outdir "${OVERTAKE_WEB_BINARY_DIR}"
    DEPENDS ${sources} "${OVERTAKE_WEB_SOURCE_DIR}/build.mjs"
            "${OVERTAKE_WEB_SOURCE_DIR}/package.json" "${OVERTAKE_WEB_SOURCE_DIR}/package-lock.json"
    WORKING_DIRECTORY "${OVERTAKE_WEB_SOURCE_DIR}"
    COMMENT "Building the web pages (viewer.html, report.html)"
    VERBATIM)
  add_custom_target(overtake_web DEPENDS "${viewer}" "${report}")
  set(${out_var} "viewer.html=${viewer}" "report.html=${report}" PARENT_SCOPE)
endfunction()

# The web tests (label "web"): the replay decoder under Node's test runner, and, outside the
# sanitizer build, the browser test: it records short drives and a small bench with the
# overtake binary, writes their pages, and opens them in Debian's Chromium (playwright-core).
# Screenshots and pages go to ${PROJECT_BINARY_DIR}/test-artifacts/browser.
function(overtake_web_tests)
  if(NOT OVERTAKE_WEB)
    return()
  endif()
  add_test(NAME web.replay_decoder
           COMMAND "${OVERTAKE_NODE}" --test test/replay.test.mjs test/report.test.mjs
           WORKING_DIRECTORY "${OVERTAKE_WEB_SOURCE_DIR}")
  set_tests_properties(web.replay_decoder PROPERTIES LABELS "web" TIMEOUT 120)
  if(NOT OVERTAKE_SANITIZE)
    add_test(NAME web.viewer_browser
             COMMAND "${OVERTAKE_NODE}" "${OVERTAKE_WEB_SOURCE_DIR}/test/browser.mjs"
                     --overtake "$<TARGET_FILE:overtake>" --source-dir "${PROJECT_SOURCE_DIR}"
                     --artifacts "${PROJECT_BINARY_DIR}/test-artifacts/browser"
             WORKING_DIRECTORY "${OVERTAKE_WEB_SOURCE_DIR}")
    set_tests_properties(web.viewer_browser PROPERTIES LABELS "web;browser" TIMEOUT 600
                         RESOURCE_LOCK chromium)
  endif()
endfunction()
