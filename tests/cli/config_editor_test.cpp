// Editing a config's values as text (tools/haptic-tune/config_editor.hpp): only the edited values
// change; comments, order and alignment stay; what cannot be edited safely is refused.
#include "config_editor.hpp"

#include <gtest/gtest.h>

#include <filesystem>

#include "scratch_dir.hpp"
#include "text_file.hpp"

namespace hapticd::daemon {
namespace {

using testing::read_file;

const char* kConfig = R"(# lab config
[servo]
rate_hz = 1000.0        # Hz

[device.model]          # what the check assumes
mass = 0.1              # kg
damping = 2.0           # N s/m

[coupling]
stiffness = 3600.0      # N/m
check = "encoder"
)";

TEST(DaemonConfigEditor, ReplacesValuesInPlaceKeepingCommentsAndAlignment) {
    const EditedConfig r = edit_config_text(kConfig,
                                            {{"device.model", "mass", 0.0987},
                                             {"device.model", "damping", 2.5},
                                             {"coupling", "stiffness", 4500.0},
                                             {"coupling", "check", std::string("exact")}},
                                            "lab.toml");
    EXPECT_EQ(r.text, R"(# lab config
[servo]
rate_hz = 1000.0        # Hz

[device.model]          # what the check assumes
mass = 0.0987           # kg
damping = 2.5           # N s/m

[coupling]
stiffness = 4500.0      # N/m
check = "exact"
)");
    ASSERT_EQ(r.changes.size(), 4u);
    EXPECT_EQ(r.changes[0].old_text, "0.1");
    EXPECT_EQ(r.changes[0].new_text, "0.0987");
    EXPECT_EQ(r.changes[3].old_text, "\"encoder\"");
}

TEST(DaemonConfigEditor, AddsMissingKeysAfterTheTableAndMissingTablesAtTheEnd) {
    const EditedConfig r = edit_config_text(
        kConfig, {{"coupling", "damping", 0.25}, {"safety", "max_force", 5.0}}, "lab.toml");
    EXPECT_NE(r.text.find("check = \"encoder\"\ndamping = 0.25\n"), std::string::npos) << r.text;
    EXPECT_NE(r.text.find("\n[safety]\nmax_force = 5.0\n"), std::string::npos) << r.text;
    EXPECT_EQ(r.text.rfind("# lab config", 0), 0u);
    EXPECT_TRUE(r.changes[0].old_text.empty());
}

TEST(DaemonConfigEditor, AValueLongerThanItsPaddingKeepsOneSpaceBeforeTheComment) {
    const EditedConfig r =
        edit_config_text(kConfig, {{"device.model", "mass", 0.012345678912345}}, "lab.toml");
    EXPECT_NE(r.text.find("mass = 0.012345678912345 # kg"), std::string::npos) << r.text;
}

// The editor splices at the value's own source region (toml++'s), so a value set with a
// dotted key or in an inline table is rewritten where it stands.
TEST(DaemonConfigEditor, RewritesAValueWhereverTheFileSetsIt) {
    EXPECT_EQ(edit_config_text("[device]\nmodel.mass = 0.1  # kg\n",
                               {{"device.model", "mass", 0.25}}, "d.toml")
                  .text,
              "[device]\nmodel.mass = 0.25 # kg\n");
    EXPECT_EQ(edit_config_text("[device]\nmodel = { mass = 0.1, damping = 2.0 }\n",
                               {{"device.model", "damping", 3.5}}, "i.toml")
                  .text,
              "[device]\nmodel = { mass = 0.1, damping = 3.5 }\n");
    // A string with a multi-byte character before the value on its line: offsets in code
    // points, not bytes.
    EXPECT_EQ(edit_config_text("[servo]\nname = \"bras gauche é\"\n[coupling]\nstiffness = 1.0\n",
                               {{"servo", "name", std::string("bras droit")}}, "u.toml")
                  .text,
              "[servo]\nname = \"bras droit\"\n[coupling]\nstiffness = 1.0\n");
    // A key added after a table's last value, which spans lines.
    EXPECT_EQ(
        edit_config_text("[a]\nlist = [1,\n  2]\n# end of a\n[b]\n", {{"a", "k", true}}, "l.toml")
            .text,
        "[a]\nlist = [1,\n  2]\nk = true\n# end of a\n[b]\n");
}

// A key cannot be added to a table without a header of its own: that would take rewriting
// the table's form, which is the user's to choose.
TEST(DaemonConfigEditor, RefusesToAddAKeyToATableWithoutAHeader) {
    for (const char* text : {"[device]\nmodel.mass = 0.1\n", "[device]\nmodel = { mass = 0.1 }\n",
                             "[device.model.x]\ny = 1\n"}) {
        SCOPED_TRACE(text);
        try {
            (void)edit_config_text(text, {{"device.model", "damping", 2.0}}, "i.toml");
            FAIL() << "added a key to a table without a header";
        } catch (const ConfigEditError& e) {
            EXPECT_NE(std::string(e.what()).find("i.toml: could not set device.model.damping"),
                      std::string::npos)
                << e.what();
        }
    }
    EXPECT_THROW(edit_config_text("[broken\n", {{"a", "b", 1.0}}, "b.toml"), ConfigEditError);
}

TEST(DaemonConfigEditor, NumbersReadBackExactlyAndStayFloats) {
    EXPECT_EQ(format_config_number(3600.0), "3600.0");
    EXPECT_EQ(format_config_number(0.1), "0.1");
    for (const double x : {1e-7, 123456.789, 2.0 / 3.0, 6.02e23}) {
        EXPECT_EQ(std::stod(format_config_number(x)), x);
    }
}

TEST(DaemonConfigEditor, WritesAtomicallyAfterABackup) {
    const testing::ScratchDir dir;
    const std::string path = dir.write("lab.toml", kConfig);
    std::filesystem::permissions(
        path, std::filesystem::perms::owner_read | std::filesystem::perms::owner_write);
    const EditedConfig r = edit_config_text(kConfig, {{"coupling", "stiffness", 1.0}}, path);
    const WrittenConfig written = write_config_with_backup(path, kConfig, r.text);
    EXPECT_EQ(written.target, std::filesystem::canonical(path).string());
    EXPECT_EQ(written.backup, written.target + ".bak");
    EXPECT_EQ(read_file(path + ".bak"), kConfig);
    EXPECT_EQ(read_file(path), r.text);
    EXPECT_FALSE(std::filesystem::exists(path + ".tmp"));
    EXPECT_EQ(std::filesystem::status(path).permissions() & std::filesystem::perms::all,
              std::filesystem::perms::owner_read | std::filesystem::perms::owner_write);
}

}  // namespace
}  // namespace hapticd::daemon
