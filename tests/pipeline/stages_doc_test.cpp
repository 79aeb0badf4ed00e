// SPDX-License-Identifier: GPL-3.0-or-later
// docs/stages.md is generated from the registry: the committed file must be the one the
// registry gives now, so a parameter's doc, default or range never drifts from the code.
#include <fstream>
#include <sstream>

#include <gtest/gtest.h>

#include "pointsurf/pipeline/registry.h"

namespace pointsurf {
namespace {

TEST(StagesDoc, CommittedFileIsTheRegistrys) {
  const std::string path = std::string(POINTSURF_DATA_DIR) + "/../docs/stages.md";
  std::ifstream in(path);
  ASSERT_TRUE(in) << path << " is missing: build/pointsurf stages --markdown > docs/stages.md";
  std::stringstream text;
  text << in.rdbuf();
  EXPECT_TRUE(text.str() == stages_markdown()) << path << " is stale: regenerate it with build/pointsurf stages --markdown > docs/stages.md";
}

TEST(StagesDoc, EveryStageAndParameterIsListed) {
  const std::string doc = stages_markdown();
  for (const StageSpec& s : registered_stages()) {
    EXPECT_NE(doc.find("\n## " + s.name + "\n"), std::string::npos) << s.name;
    for (const ParamSpec& p : s.params) EXPECT_NE(doc.find("| `" + p.name + "` |"), std::string::npos) << s.name << "." << p.name;
  }
}

}  // namespace
}  // namespace pointsurf
