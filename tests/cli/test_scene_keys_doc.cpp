// `weft help scene-keys`: the key tables of docs/scene-format.md are exactly what the parameter table
// generates (so the page cannot drift from the loader), the terminal text names every key, and the
// topic parses with and without --markdown.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <string_view>
#include <vector>

#include "weft/parameters.h"

#include "cli_args.h"
#include "scene_keys_help.h"

namespace weft::cli {
namespace {

const std::filesystem::path kDoc = std::filesystem::path(WEFT_SOURCE_DIR) / "docs" / "scene-format.md";

// The generated blocks of the page, by section: the lines between a section's opening comment and
// the closing one.
std::map<std::string, std::string> generated_blocks(const std::string& page) {
    std::map<std::string, std::string> blocks;
    std::istringstream in(page);
    std::string section, block;
    bool inside = false;
    for (std::string line; std::getline(in, line);) {
        if (!inside) {
            for (const std::string_view s : scene_key_sections()) {
                if (line == scene_keys_begin(s)) {
                    section = std::string(s);
                    block.clear();
                    inside = true;
                }
            }
        } else if (line == kSceneKeysEnd) {
            EXPECT_FALSE(blocks.contains(section)) << section << " has two generated tables";
            blocks[section] = block;
            inside = false;
        } else {
            block += line + "\n";
        }
    }
    EXPECT_FALSE(inside) << "the table of " << section << " is not closed by " << kSceneKeysEnd;
    return blocks;
}

TEST(SceneKeysDoc, TheSceneFormatTablesAreTheGeneratedOnes) {
    std::ifstream in(kDoc, std::ios::binary);
    ASSERT_TRUE(in) << kDoc;
    std::ostringstream page;
    page << in.rdbuf();
    const std::map<std::string, std::string> blocks = generated_blocks(page.str());
    for (const std::string_view section : scene_key_sections()) {
        const auto found = blocks.find(std::string(section));
        ASSERT_NE(found, blocks.end()) << "docs/scene-format.md has no table for [" << section << "]: paste it from "
                                       << "'weft help scene-keys --markdown'";
        EXPECT_EQ(found->second, scene_keys_markdown(section))
            << "docs/scene-format.md differs from the parameter table for [" << section << "]: paste the table from "
            << "'weft help scene-keys --markdown' (and describe the change in the page's prose)";
    }
    EXPECT_EQ(blocks.size(), scene_key_sections().size());
}

TEST(SceneKeysDoc, TheTextNamesEveryKeyWithItsRangeAndUnit) {
    const std::string text = scene_keys_text();
    for (const Parameter& p : parameter_table()) {
        SCOPED_TRACE(p.key());
        const auto at = text.find("  " + p.key() + "  (");
        ASSERT_NE(at, std::string::npos);
        const std::string line = text.substr(at, text.find('\n', at) - at);
        EXPECT_NE(line.find(parameter_range_text(p)), std::string::npos) << line;
        if (!p.unit.empty()) {
            EXPECT_NE(line.find(std::string(", ") + std::string(p.unit)), std::string::npos) << line;
        }
    }
    EXPECT_NE(text.find("solver.dt  (number, s; default 0.0166667; [1e-5, 0.1]; live)"), std::string::npos);
    EXPECT_NE(text.find("cloth.density  (number, kg/m²; default 0.2; (0, 100]; re-cook)"), std::string::npos);
}

TEST(SceneKeysDoc, HelpTopicParses) {
    const std::vector<std::string_view> plain{"help", "scene-keys"};
    const Invocation a = parse_command_line(plain);
    EXPECT_EQ(a.command, Invocation::Command::Help);
    EXPECT_EQ(a.help_topic, kSceneKeysTopic);
    EXPECT_FALSE(a.help_markdown);
    const std::vector<std::string_view> markdown{"help", "scene-keys", "--markdown"};
    EXPECT_TRUE(parse_command_line(markdown).help_markdown);
    const std::vector<std::string_view> bad_flag{"help", "scene-keys", "--html"};
    EXPECT_THROW((void)parse_command_line(bad_flag), UsageError);
    const std::vector<std::string_view> not_for_commands{"help", "run", "--markdown"};
    EXPECT_THROW((void)parse_command_line(not_for_commands), UsageError);
    const std::vector<std::string_view> typo{"help", "scene-kyes"};
    try {
        (void)parse_command_line(typo);
        ADD_FAILURE() << "no error";
    } catch (const UsageError& e) {
        EXPECT_NE(std::string(e.what()).find("did you mean 'scene-keys'"), std::string::npos) << e.what();
    }
}

}  // namespace
}  // namespace weft::cli
