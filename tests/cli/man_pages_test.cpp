// The man pages (man/hapticd.8, man/haptic-tune.1, man/hapticd.toml.5) held to the programs
// they describe. The programs are asked, not their sources: the options come from --help,
// the subcommands from `haptic-tune --help`, and the config keys from hapticd's own refusal
// of an unknown key ("[servo] x = 1 is not a known key: allowed rate_hz, realtime, ..."), so
// an option or a key added without its entry in a page fails here.
//
// What a page must have, in roff:
//   - every long option as `\-\-name` in the tag of a `.TP` entry, under `.SH OPTIONS`
//     (haptic-tune.1: a command's options under its `.SS COMMAND`);
//   - every config key as a `.TP` entry tagged `.B key`, in a `.SS` whose heading names its
//     table in brackets (`.SS [servo]`, `.SS "[device.usb], [device.hid], ..."`), and every
//     table as such a heading.
#include <gtest/gtest.h>

#include <cctype>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "run_command.hpp"
#include "scratch_dir.hpp"
#include "text_file.hpp"

namespace hapticd {
namespace {

using hapticd::testing::CommandResult;
using hapticd::testing::lines_of_text;
using hapticd::testing::read_file;
using hapticd::testing::run_command;
using hapticd::testing::ScratchDir;

const std::string kSource = HAPTICD_SOURCE_DIR;
const std::string kHapticdPage = kSource + "/man/hapticd.8";
const std::string kHapticTunePage = kSource + "/man/haptic-tune.1";
const std::string kConfigPage = kSource + "/man/hapticd.toml.5";
const std::string kHapticctlPage = kSource + "/man/hapticctl.1";

std::string quoted(const std::string& path) { return "'" + path + "'"; }

std::vector<std::string> lines_of(const std::string& text) { return lines_of_text(text); }

std::vector<std::string> split(const std::string& text, const std::string& separator) {
    std::vector<std::string> parts;
    std::size_t from = 0;
    for (std::size_t at = text.find(separator); at != std::string::npos;
         at = text.find(separator, from)) {
        parts.push_back(text.substr(from, at - from));
        from = at + separator.size();
    }
    parts.push_back(text.substr(from));
    return parts;
}

bool starts_with(const std::string& text, const std::string& prefix) {
    return text.rfind(prefix, 0) == 0;
}

// --- What the programs print -------------------------------------------------------------

/// The long options of a CLI11 help text. An option's line starts with two spaces and its
/// names ("  -h,--help", "  --config TEXT:FILE REQUIRED"); its description, and the lines of
/// the other sections, do not start with "  -".
std::vector<std::string> long_options_in_help(const std::string& help) {
    std::vector<std::string> options;
    for (const std::string& line : lines_of(help)) {
        if (!starts_with(line, "  -")) continue;
        const std::string names = line.substr(2, line.find(' ', 2) - 2);
        for (const std::string& name : split(names, ",")) {
            if (starts_with(name, "--")) options.push_back(name);
        }
    }
    return options;
}

/// The subcommands a CLI11 help text lists under "Subcommands:", one a line.
std::vector<std::string> subcommands_in_help(const std::string& help) {
    std::vector<std::string> names;
    bool listing = false;
    for (const std::string& line : lines_of(help)) {
        if (line == "Subcommands:") {
            listing = true;
        } else if (listing && starts_with(line, "  ") &&
                   std::isalpha(static_cast<unsigned char>(line[2])) != 0) {
            names.push_back(line.substr(2, line.find(' ', 2) - 2));
        } else if (listing && line.empty()) {
            break;
        }
    }
    return names;
}

std::string help_of(const std::string& program, const std::string& arguments) {
    const CommandResult r = run_command(program + " " + arguments + " --help");
    EXPECT_EQ(r.exit_code, 0) << program << " " << arguments << " --help: " << r.err;
    return r.out;
}

// --- What a page says --------------------------------------------------------------------

/// `--no-status` as roff writes it: `\-\-no\-status`.
std::string roff_dashes(const std::string& text) {
    std::string roff;
    for (const char c : text) roff += c == '-' ? std::string("\\-") : std::string(1, c);
    return roff;
}

/// True when `roff` names `option` itself, not a longer one it begins (--model in
/// --models, --force-filter in --force-filter-damping).
bool names_option(const std::string& roff, const std::string& option) {
    const std::string wanted = roff_dashes(option);
    for (std::size_t at = roff.find(wanted); at != std::string::npos;
         at = roff.find(wanted, at + 1)) {
        const std::string after = roff.substr(at + wanted.size(), 2);
        const bool longer =
            !after.empty() && (std::isalnum(static_cast<unsigned char>(after[0])) != 0 ||
                               after[0] == '_' || after == "\\-");
        if (!longer) return true;
    }
    return false;
}

/// A macro's first argument: `.B rate_hz` -> rate_hz, `.SS "[device.usb], ..."` -> the text
/// inside the quotes.
std::string first_argument(const std::string& line) {
    const std::size_t start = line.find_first_not_of(' ', line.find(' '));
    if (start == std::string::npos) return "";
    if (line[start] == '"') return line.substr(start + 1, line.find('"', start + 1) - start - 1);
    return line.substr(start, line.find(' ', start) - start);
}

/// One `.SH` or `.SS` of a page: its heading and the roff up to the next one.
struct Section {
    std::string heading;
    std::vector<std::string> lines;

    /// The tag lines of its `.TP` entries (`.BI \-\-config " FILE"`), one a line.
    std::string tags() const {
        std::string all;
        for (std::size_t i = 0; i + 1 < lines.size(); ++i) {
            if (lines[i] == ".TP") all += lines[i + 1] + "\n";
        }
        return all;
    }
    /// The keys its `.TP` entries are for: the tags written `.B key`.
    std::vector<std::string> entries() const {
        std::vector<std::string> keys;
        for (const std::string& tag : lines_of(tags())) {
            if (starts_with(tag, ".B ")) keys.push_back(first_argument(tag));
        }
        return keys;
    }
};

class ManPage {
  public:
    explicit ManPage(const std::string& path) {
        for (const std::string& line : lines_of(read_file(path))) {
            if (starts_with(line, ".SH ") || starts_with(line, ".SS ")) {
                std::string heading = line.substr(4);
                if (!heading.empty() && heading.front() == '"') heading = first_argument(line);
                sections_.push_back({heading, {}});
            } else if (!sections_.empty()) {
                sections_.back().lines.push_back(line);
            }
        }
    }

    /// The section headed exactly `heading` (`.SS size`), or null.
    const Section* section(const std::string& heading) const {
        for (const Section& s : sections_) {
            if (s.heading == heading) return &s;
        }
        return nullptr;
    }

    /// Whether some heading names `table`, "[servo]", in its brackets.
    bool has_table(const std::string& table) const {
        for (const Section& s : sections_) {
            if (s.heading.find(table) != std::string::npos) return true;
        }
        return false;
    }

    /// Whether a section whose heading names `table` has an entry for `key`.
    bool has_key(const std::string& table, const std::string& key) const {
        for (const Section& s : sections_) {
            if (s.heading.find(table) == std::string::npos) continue;
            for (const std::string& tag : s.entries()) {
                if (tag == key) return true;
            }
        }
        return false;
    }

  private:
    std::vector<Section> sections_;
};

// --- a. The pages format cleanly ---------------------------------------------------------

TEST(ManPages, FormatWithoutAWarning) {
    for (const std::string& page : {kHapticdPage, kHapticTunePage, kConfigPage, kHapticctlPage}) {
        SCOPED_TRACE(page);
        const CommandResult r = run_command("groff -man -ww -z " + quoted(page));
        EXPECT_EQ(r.exit_code, 0) << r.err;
        EXPECT_EQ(r.err, "");
    }
}

// --- b. Every option has its entry -------------------------------------------------------

/// The tags of `heading`'s entries, or a failure when the page has no such section.
std::string option_tags(const ManPage& page, const std::string& heading) {
    const Section* section = page.section(heading);
    EXPECT_NE(section, nullptr) << "no section " << heading;
    return section != nullptr ? section->tags() : "";
}

TEST(ManPages, HapticdPageHasAnEntryForEveryOptionOfItsHelp) {
    const std::vector<std::string> options = long_options_in_help(help_of(HAPTICD_BIN, ""));
    // --help, --config, --duration, --summary, --log, --identify, --lockstep, --no-status,
    // --list-plugins, --parent-lifeline at the least.
    ASSERT_GE(options.size(), 10u) << "the options of hapticd --help were not found";
    const ManPage page(kHapticdPage);
    const std::string entries = option_tags(page, "OPTIONS");
    for (const std::string& option : options) {
        EXPECT_TRUE(names_option(entries, option)) << "no entry for " << option << " in OPTIONS";
    }
}

TEST(ManPages, HapticTunePageHasASectionPerCommandWithAnEntryPerOption) {
    const ManPage page(kHapticTunePage);
    const std::string help = help_of(HAPTIC_TUNE, "");
    const std::string common = option_tags(page, "OPTIONS");
    const std::vector<std::string> options = long_options_in_help(help);
    ASSERT_FALSE(options.empty()) << "the options of haptic-tune --help were not found";
    for (const std::string& option : options) {
        EXPECT_TRUE(names_option(common, option)) << "no entry for " << option << " in OPTIONS";
    }
    const std::vector<std::string> commands = subcommands_in_help(help);
    // size, check, plot, zwidth, diag, identify, autotune.
    ASSERT_GE(commands.size(), 7u) << "the commands of haptic-tune --help were not found";
    for (const std::string& command : commands) {
        SCOPED_TRACE("haptic-tune " + command);
        const std::string entries = option_tags(page, command);
        const std::vector<std::string> its = long_options_in_help(help_of(HAPTIC_TUNE, command));
        ASSERT_GE(its.size(), 4u) << "the options of haptic-tune " << command << " --help";
        for (const std::string& option : its) {
            // --help is every command's; the page gives it once, under OPTIONS.
            EXPECT_TRUE(names_option(option == "--help" ? common : entries, option))
                << "no entry for " << option << " in .SS " << command;
        }
    }
}

TEST(ManPages, HapticctlPageHasASectionPerCommandWithAnEntryPerOption) {
    const ManPage page(kHapticctlPage);
    const std::string help = help_of(HAPTICCTL_BIN, "");
    const std::string common = option_tags(page, "OPTIONS");
    const std::vector<std::string> options = long_options_in_help(help);
    // --help, --version, --instance, --socket.
    ASSERT_GE(options.size(), 4u) << "the options of hapticctl --help were not found";
    for (const std::string& option : options) {
        EXPECT_TRUE(names_option(common, option)) << "no entry for " << option << " in OPTIONS";
    }
    const std::vector<std::string> commands = subcommands_in_help(help);
    // status, watch, arm, disarm, reset.
    ASSERT_GE(commands.size(), 5u) << "the commands of hapticctl --help were not found";
    for (const std::string& command : commands) {
        SCOPED_TRACE("hapticctl " + command);
        ASSERT_NE(page.section(command), nullptr) << "no .SS " << command;
        const std::string entries = page.section(command)->tags();
        for (const std::string& option : long_options_in_help(help_of(HAPTICCTL_BIN, command))) {
            EXPECT_TRUE(names_option(option == "--help" ? common : entries, option))
                << "no entry for " << option << " in .SS " << command;
        }
    }
}

// --- c. Every config key has its entry ---------------------------------------------------

const std::string kUnknownKey = "not_a_key_of_any_table";
const std::string kUnknown = kUnknownKey + " = 1\n";
const std::string kModel = "[device.model]\nmass = 0.1\ndamping = 2.0\n";
const std::string kCoupling = "[coupling]\nstiffness = 3000.0\n";
const std::string kRunnable = kModel + kCoupling;

/// A config that hapticd refuses only for an unknown key in `table` ("" for the top level).
struct Probe {
    std::string table;
    std::string config;
};

std::vector<Probe> probes() {
    const std::string operators =
        "[operator]\nhand_mass = 1\ngrip_stiffness = 0\ngrip_damping = 1\narm_stiffness = 0\n"
        "arm_damping = 1\n";
    std::vector<Probe> all = {
        {"", kUnknown + kRunnable},
        {"[servo]", kRunnable + "[servo]\n" + kUnknown},
        {"[device]", "[device]\n" + kUnknown + kRunnable},
        {"[device.model]", kModel + kUnknown + kCoupling},
        {"[coupling]", kRunnable + kUnknown},
        {"[operator]", kModel + kCoupling + "check = \"exact\"\n" + operators + kUnknown},
        {"[scene]", kRunnable + "[scene]\n" + kUnknown},
        {"[safety]", kRunnable + "[safety]\n" + kUnknown},
        {"[identify]", kRunnable + "[identify]\n" + kUnknown},
        {"[device.sim]", kRunnable + "[device.sim]\n" + kUnknown},
        {"[device.sim.faults]", kRunnable + "[device.sim.faults]\n" + kUnknown},
        {"[device.sim.human.push]", kRunnable + "[device.sim.human]\nmodel = \"stiff-grasp\"\n" +
                                        "push = { to = 0.01, " + kUnknownKey + " = 1 }\n"},
        {"[device.usb]", "[device]\nplugin = \"usb\"\n" + kRunnable + "[device.usb]\n" + kUnknown},
        {"[device.hid]", "[device]\nplugin = \"hid\"\n" + kRunnable + "[device.hid]\n" + kUnknown},
        {"[device.serial]", "[device]\nplugin = \"serial\"\n" + kRunnable +
                                "[device.serial]\nport = \"/dev/null\"\n" + kUnknown},
    };
    // Each human model reads only its own keys: together they list them all.
    for (const char* model : {"hands-off", "heavy-hand", "stiff-grasp", "two-mass-grasp"}) {
        all.push_back({"[device.sim.human]",
                       kRunnable + "[device.sim.human]\nmodel = \"" + model + "\"\n" + kUnknown});
    }
    return all;
}

/// What hapticd lists as allowed when it refuses the probe's unknown key: tables as
/// "[device.model]", keys as "mass". The message, "lab.toml:8: [servo] not_a_key... = 1 is
/// not a known key: allowed rate_hz, realtime, priority, cpu", may end with the document
/// that lists the keys, "(docs/sim-device.md)".
std::vector<std::string> allowed_by_hapticd(const ScratchDir& dir, const Probe& probe, int n) {
    const std::string config = dir.write("probe-" + std::to_string(n) + ".toml", probe.config);
    const CommandResult r = run_command(std::string(HAPTICD_BIN) + " --config " + quoted(config) +
                                        " --lockstep --duration 0.01 --no-status");
    EXPECT_EQ(r.exit_code, 2) << r.err;
    const std::string refusal = (probe.table.empty() ? ": " : probe.table + " ") + kUnknownKey +
                                " = 1 is not a known key: allowed ";
    const std::size_t at = r.err.find(refusal);
    if (at == std::string::npos) {
        ADD_FAILURE() << "hapticd did not refuse the unknown key as expected:\n" << r.err;
        return {};
    }
    const std::size_t from = at + refusal.size();
    std::string list = r.err.substr(from, r.err.find('\n', from) - from);
    if (const std::size_t doc = list.rfind(" ("); doc != std::string::npos && list.back() == ')') {
        list.erase(doc);
    }
    return split(list, ", ");
}

/// "[[device.sim.human]]" -> "[device.sim.human]": a heading that names the table names both.
std::string as_table(const std::string& item) {
    return starts_with(item, "[[") ? item.substr(1, item.size() - 2) : item;
}

TEST(ManPages, ConfigPageHasAnEntryForEveryKeyHapticdAccepts) {
    const ManPage page(kConfigPage);
    const ScratchDir dir;
    int n = 0;
    for (const Probe& probe : probes()) {
        const std::string table = probe.table.empty() ? "the top level" : probe.table;
        SCOPED_TRACE(table + ":\n" + probe.config);
        const std::vector<std::string> allowed = allowed_by_hapticd(dir, probe, ++n);
        ASSERT_FALSE(allowed.empty() || allowed.front().empty()) << "no allowed keys for " << table;
        for (const std::string& item : allowed) {
            if (starts_with(item, "[")) {
                EXPECT_TRUE(page.has_table(as_table(item))) << "no .SS heading names " << item;
            } else {
                EXPECT_TRUE(page.has_key(probe.table, item))
                    << "no .TP entry \".B " << item << "\" under a heading naming " << table;
            }
        }
    }
}

/// The lines between .EX and .EE in `section`, as the reader sees them.
std::string example_text(const Section& section) {
    std::string text;
    bool inside = false;
    for (const std::string& line : section.lines) {
        if (line == ".EX" || line == ".EE") {
            inside = line == ".EX";
            continue;
        }
        if (!inside) continue;
        std::string plain;
        for (std::size_t i = 0; i < line.size(); ++i) {
            if (line.compare(i, 2, "\\-") == 0) {
                plain += '-';
                ++i;
            } else if (line.compare(i, 2, "\\e") == 0) {
                plain += '\\';
                ++i;
            } else if (line.compare(i, 2, "\\&") == 0) {
                ++i;
            } else {
                plain += line[i];
            }
        }
        text += plain + "\n";
    }
    return text;
}

TEST(ManPages, ConfigPageExampleIsTheDefaultConfig) {
    const ManPage page(kConfigPage);
    const Section* example = page.section("EXAMPLE");
    ASSERT_NE(example, nullptr) << "no .SH EXAMPLE in " << kConfigPage;
    EXPECT_EQ(example_text(*example), read_file(kSource + "/config/hapticd.toml"));
}

}  // namespace
}  // namespace hapticd
