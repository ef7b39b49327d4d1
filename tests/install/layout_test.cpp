// Which plugin directory and chart script an executable uses: its build tree's, or its
// installation's, never the other (install/layout.hpp).
#include "hapticd/install/layout.hpp"

#include <gtest/gtest.h>

#include <string>

namespace {

using hapticd::install::layout;
using hapticd::install::layout_for;

TEST(InstallLayout, ABuildTreeExecutableUsesItsBuildTree) {
    const auto build = layout_for(HAPTICD_TEST_BIN_DIR "/hapticd");
    EXPECT_TRUE(build.build_tree);
    EXPECT_EQ(build.plugin_dir, HAPTICD_TEST_BUILD_PLUGIN_DIR);
    EXPECT_TRUE(build.chart_script.ends_with("/tools/plot/hapticd_chart.py")) << build.chart_script;
}

TEST(InstallLayout, ThisTestIsABuildTreeExecutable) {
    EXPECT_TRUE(layout().build_tree) << layout().executable;
    EXPECT_EQ(layout().plugin_dir, HAPTICD_TEST_BUILD_PLUGIN_DIR);
}

TEST(InstallLayout, AnInstalledExecutableUsesItsOwnPrefixWhereverThatIs) {
    for (const std::string prefix : {"/usr", "/usr/local", "/tmp/stage/opt/hapticd"}) {
        const auto installed = layout_for(prefix + "/bin/hapticd");
        EXPECT_FALSE(installed.build_tree) << prefix;
        EXPECT_EQ(installed.executable, prefix + "/bin/hapticd");
        EXPECT_EQ(installed.plugin_dir, prefix + "/" HAPTICD_TEST_PLUGIN_INSTALL_DIR) << prefix;
        EXPECT_EQ(installed.chart_script, prefix + "/share/hapticd/hapticd_chart.py") << prefix;
    }
}

TEST(InstallLayout, AnExecutableBesideTheBuildTreeIsNotTheBuildTrees) {
    // The build tree's parent, or a bin/ inside it that is not the output directory.
    const auto beside = layout_for(HAPTICD_TEST_BIN_DIR "/../hapticd");
    EXPECT_FALSE(beside.build_tree) << beside.executable;
    const auto inside = layout_for(HAPTICD_TEST_BIN_DIR "/sub/hapticd");
    EXPECT_FALSE(inside.build_tree) << inside.executable;
    EXPECT_NE(inside.plugin_dir, HAPTICD_TEST_BUILD_PLUGIN_DIR);
}

}  // namespace
