#include <gtest/gtest.h>

#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <string>
#include <vector>

#include "tactile_common/parameter_testing.hpp"
#include "tactile_common/parameters.hpp"

using tactile_common::load_node_parameters_from_string;
using tactile_common::ParamError;
using tactile_common::ParamMap;

namespace {

ParamMap defaults() {
  ParamMap d("tdorc_filter", "defaults");
  d.set("window", int64_t{100});
  d.set("contact_threshold", 20.0);
  d.set("mode", std::string("tdorc"));
  d.set("absolute_threshold", false);
  d.set("bandpass_b", std::vector<double>{0.0564, 0.0, -0.0564});
  d.set("kf.q", 0.01);
  return d;
}

std::string error_of(const std::string& yaml) {
  try {
    load_node_parameters_from_string(yaml, "config/x.yaml", "tdorc_filter", defaults());
  } catch (const ParamError& e) {
    return e.what();
  }
  return "";
}

}  // namespace

// Issue 32: a file without the node's section (a misspelt or another node's
// name) ran the node on its compiled defaults without a word; now it names
// the file, the node, what was expected and the sections it found.
TEST(Parameters, FileWithoutTheNodesSectionIsAnError) {
  const auto msg = error_of("tdorc_filtr:\n  ros__parameters: {window: 50}\n");
  EXPECT_NE(msg.find("config/x.yaml: no section for node /tdorc_filter"), std::string::npos) << msg;
  EXPECT_NE(msg.find("expected a 'tdorc_filter:' (or '/**/tdorc_filter:') section with 'ros__parameters'"),
            std::string::npos) << msg;
  EXPECT_NE(msg.find("sections in the file: tdorc_filtr"), std::string::npos) << msg;
  // The catch-all section alone does not name the node: still an error.
  EXPECT_NE(error_of("/**:\n  ros__parameters: {window: 50}\n").find("no section for node"), std::string::npos);
  // A section that names the node with nothing in it keeps the defaults on purpose.
  auto p = load_node_parameters_from_string("tdorc_filter:\n  ros__parameters:\n", "x.yaml", "tdorc_filter",
                                            defaults());
  EXPECT_EQ(p.get_int("window", 0, 1000), 100);
}

TEST(Parameters, EmptyFileIsAnError) {
  for (const char* yaml : {"", "\n  \n", "# only a comment\n"}) {
    const auto msg = error_of(yaml);
    EXPECT_NE(msg.find("config/x.yaml: empty parameter file: expected a 'tdorc_filter:'"), std::string::npos)
        << "[" << yaml << "] " << msg;
  }
}

TEST(Parameters, NodeSectionOverridesWildcardWhichOverridesDefaults) {
  const std::string yaml =
      "/**:\n  ros__parameters:\n    window: 50\n    contact_threshold: 30.0\n    other_node_key: 1\n"
      "/whisker/left/tdorc_filter:\n  ros__parameters:\n    window: 80\n    mode: tdoc\n"
      "    kf:\n      q: 0.5\n    bandpass_b: [1, 0, -1]\n";
  auto p = load_node_parameters_from_string(yaml, "x.yaml", "/whisker/left/tdorc_filter", defaults());
  EXPECT_EQ(p.get_int("window", 0, 1000), 80);
  EXPECT_DOUBLE_EQ(p.get_double("contact_threshold"), 30.0);
  EXPECT_EQ(p.get_string("mode"), "tdoc");
  EXPECT_DOUBLE_EQ(p.get_double("kf.q"), 0.5);
  EXPECT_EQ(p.get_double_array("bandpass_b"), (std::vector<double>{1.0, 0.0, -1.0}));
  EXPECT_EQ(p.source(), "x.yaml");
}

TEST(Parameters, SectionsMatchFullyQualifiedNamesLikeRos2) {
  const std::string yaml =
      "/**/tdorc_filter:\n  ros__parameters:\n    window: 60\n"
      "/whisker/right/tdorc_filter:\n  ros__parameters:\n    window: 70\n"
      "/whisker/*/tdorc_filter:\n  ros__parameters:\n    mode: tdoc\n"
      "tdorc_filter:\n  ros__parameters:\n    window: 90\n";
  auto left = load_node_parameters_from_string(yaml, "x.yaml", "/whisker/left/tdorc_filter", defaults());
  auto right = load_node_parameters_from_string(yaml, "x.yaml", "/whisker/right/tdorc_filter", defaults());
  auto root = load_node_parameters_from_string(yaml, "x.yaml", "tdorc_filter", defaults());
  auto deep = load_node_parameters_from_string(yaml, "x.yaml", "/a/b/c/tdorc_filter", defaults());
  EXPECT_EQ(left.get_int("window", 0, 1000), 60);   // only the '**' section applies
  EXPECT_EQ(left.get_string("mode"), "tdoc");
  EXPECT_EQ(right.get_int("window", 0, 1000), 70);  // exact name beats the wildcard
  EXPECT_EQ(root.get_int("window", 0, 1000), 90);   // a bare name is the root namespace
  EXPECT_EQ(root.get_string("mode"), "tdorc");
  EXPECT_EQ(deep.get_int("window", 0, 1000), 60);
  EXPECT_EQ(deep.get_string("mode"), "tdorc");  // '*' is exactly one token
  EXPECT_EQ(left.node(), "tdorc_filter");
}

TEST(Parameters, IntegerAcceptedForDouble) {
  auto p = load_node_parameters_from_string(
      "tdorc_filter:\n  ros__parameters:\n    contact_threshold: 25\n", "x.yaml", "tdorc_filter",
      defaults());
  EXPECT_DOUBLE_EQ(p.get_double("contact_threshold"), 25.0);
}

TEST(Parameters, UnknownKeyNamesFileKeyAndReason) {
  const auto msg = error_of("tdorc_filter:\n  ros__parameters:\n    windw: 10\n");
  EXPECT_NE(msg.find("config/x.yaml"), std::string::npos) << msg;
  EXPECT_NE(msg.find("tdorc_filter.ros__parameters.windw"), std::string::npos) << msg;
  EXPECT_NE(msg.find("unknown parameter"), std::string::npos) << msg;
}

TEST(Parameters, WrongTypeNamesExpectedAndActual) {
  const auto msg = error_of("tdorc_filter:\n  ros__parameters:\n    window: ten\n");
  EXPECT_NE(msg.find("window: expected integer, got string"), std::string::npos) << msg;
  const auto msg2 = error_of("tdorc_filter:\n  ros__parameters:\n    absolute_threshold: 3.5\n");
  EXPECT_NE(msg2.find("expected bool, got double"), std::string::npos) << msg2;
}

TEST(Parameters, SyntaxErrorNamesLine) {
  const auto msg = error_of("tdorc_filter:\n  ros__parameters:\n    window: [1, 2\n");
  EXPECT_NE(msg.find("YAML syntax error at line"), std::string::npos) << msg;
  EXPECT_NE(msg.find("config/x.yaml"), std::string::npos) << msg;
}

TEST(Parameters, MissingRosParametersKey) {
  const auto msg = error_of("tdorc_filter:\n  window: 3\n");
  EXPECT_NE(msg.find("expected a map with key 'ros__parameters'"), std::string::npos) << msg;
}

namespace {
std::string file_error(const std::string& path) {
  try {
    tactile_common::load_node_parameters(path, "/whisker/left/tdorc_filter", defaults());
  } catch (const ParamError& e) {
    return e.what();
  }
  return "";
}
}  // namespace

TEST(Parameters, MissingFile) {
  EXPECT_EQ(file_error("does/not/exist.yaml"),
            "does/not/exist.yaml: parameter file of node /whisker/left/tdorc_filter missing (no such file)");
}

// Issue 32: std::ifstream opens a directory and reads it as empty, so a
// directory named like a parameter file ran the node on its defaults.
TEST(Parameters, DirectoryOrEmptyOrMisnamedFileIsAnError) {
  namespace fs = std::filesystem;
  const fs::path dir = fs::temp_directory_path() / ("tactile_params_" + std::to_string(::getpid()));
  fs::create_directories(dir / "tdorc_filter.yaml");
  EXPECT_EQ(file_error((dir / "tdorc_filter.yaml").string()),
            (dir / "tdorc_filter.yaml").string() +
                ": parameter file of node /whisker/left/tdorc_filter is not a file (a directory)");
  std::ofstream(dir / "empty.yaml").flush();
  EXPECT_NE(file_error((dir / "empty.yaml").string()).find((dir / "empty.yaml").string() + ": empty parameter file"),
            std::string::npos);
  std::ofstream(dir / "other.yaml") << "/**/tdorc_filtr:\n  ros__parameters:\n    window: 50\n";
  EXPECT_NE(file_error((dir / "other.yaml").string()).find("no section for node /whisker/left/tdorc_filter"),
            std::string::npos);
  std::ofstream(dir / "good.yaml") << "/**/tdorc_filter:\n  ros__parameters:\n    window: 50\n";
  EXPECT_EQ(tactile_common::load_node_parameters((dir / "good.yaml").string(), "/whisker/left/tdorc_filter",
                                                 defaults())
                .get_int("window", 0, 1000),
            50);
  fs::remove_all(dir);
}

TEST(Parameters, GetterOfUndeclaredKeyThrows) {
  auto p = defaults();
  EXPECT_THROW(p.get_double("nope"), ParamError);
  EXPECT_THROW(p.get_string("window"), ParamError);
}

TEST(Parameters, ErrorHelperFormatsLikeLoader) {
  auto p = load_node_parameters_from_string("tdorc_filter:\n  ros__parameters: {}\n", "cfg.yaml", "tdorc_filter",
                                            defaults());
  EXPECT_STREQ(p.error("window", "must be >= 2, got 1").what(),
               "cfg.yaml: tdorc_filter.ros__parameters.window: must be >= 2, got 1");
}

TEST(Parameters, ErrorsNameTheOriginOfEachKey) {
  auto p = load_node_parameters_from_string("tdorc_filter:\n  ros__parameters:\n    window: 1\n",
                                            "file.yaml", "tdorc_filter", defaults());
  ParamMap launch("tdorc_filter", "launch overrides");
  launch.set("mode", std::string("tdoc"));
  p.merge_from(launch);
  EXPECT_EQ(p.origin("window"), "file.yaml");
  EXPECT_EQ(p.origin("mode"), "launch overrides");
  EXPECT_NE(std::string(p.error("window", "bad").what()).find("file.yaml:"), std::string::npos);
  EXPECT_NE(std::string(p.error("mode", "bad").what()).find("launch overrides:"), std::string::npos);
}

TEST(Parameters, ErrorFromValidateMessageNamesTheField) {
  ParamMap m("tdorc_filter", "defaults");
  m.set("window", int64_t{1});
  m.set("bandpass_a", std::vector<double>{1.0, -2.0, 1.0});
  // "<Type>.<field>: <reason>" -> key <field>, reason after ": ".
  EXPECT_EQ(std::string(m.error_from(std::invalid_argument("TdorcParams.window: must be >= 2, got 1")).what()),
            "defaults: tdorc_filter.ros__parameters.window: must be >= 2, got 1");
  // An indexed field "<field>[i]" names the array parameter.
  EXPECT_EQ(std::string(m.error_from(std::invalid_argument("TdorcParams.bandpass_a[0]: must be 1")).what()),
            "defaults: tdorc_filter.ros__parameters.bandpass_a: must be 1");
}

// Range-checked integer getters: the value is checked as the 64-bit integer it
// was given as, before it is narrowed, and every failure names the file, the
// key, the range and the value as given.
namespace {

ParamMap ints() {
  ParamMap m("tdorc_filter", "cfg.yaml");
  m.set("k", int64_t{0});
  return m;
}

std::string int_error(int64_t value, int lo, int hi) {
  ParamMap m = ints();
  m.set("k", value);
  try {
    m.get_int("k", lo, hi);
  } catch (const ParamError& e) {
    return e.what();
  }
  return "";
}

}  // namespace

TEST(IntegerParameters, InRangeAndAtTheBoundsIsTheValue) {
  ParamMap m = ints();
  for (const int64_t v : {int64_t{2}, int64_t{50}, int64_t{100}}) {
    m.set("k", v);
    EXPECT_EQ(m.get_int("k", 2, 100), v);
  }
  m.set("k", int64_t{-7});
  EXPECT_EQ(m.get_int("k", -7, -7), -7);  // a one-value range
}

TEST(IntegerParameters, OneOutsideEitherBoundIsRejectedWithKeyRangeAndValue) {
  EXPECT_EQ(int_error(1, 2, 100), "cfg.yaml: tdorc_filter.ros__parameters.k: must be in [2, 100], got 1");
  EXPECT_EQ(int_error(101, 2, 100), "cfg.yaml: tdorc_filter.ros__parameters.k: must be in [2, 100], got 101");
  EXPECT_EQ(int_error(-1, 0, 10), "cfg.yaml: tdorc_filter.ros__parameters.k: must be in [0, 10], got -1");
}

TEST(IntegerParameters, ValuesThatWrapWhenNarrowedToIntAreRejected) {
  // static_cast<int>(2^32 + 10) == 10, which [2, 100] would have accepted.
  const int64_t wraps_to_10 = (int64_t{1} << 32) + 10;
  EXPECT_EQ(int_error(wraps_to_10, 2, 100),
            "cfg.yaml: tdorc_filter.ros__parameters.k: must be in [2, 100], got 4294967306");
  // Even with the int's whole range allowed, 2^32 + 10 is not an int.
  const int lo = std::numeric_limits<int>::min(), hi = std::numeric_limits<int>::max();
  EXPECT_EQ(int_error(wraps_to_10, lo, hi),
            "cfg.yaml: tdorc_filter.ros__parameters.k: must be in [-2147483648, 2147483647], got 4294967306");
  EXPECT_NE(int_error(int64_t{hi} + 1, lo, hi), "");
  EXPECT_NE(int_error(int64_t{lo} - 1, lo, hi), "");
  EXPECT_EQ(int_error(hi, lo, hi), "");
  EXPECT_EQ(int_error(lo, lo, hi), "");
}

TEST(IntegerParameters, NegativeIsOutOfRangeForUnsignedTypes) {
  ParamMap m = ints();
  m.set("k", int64_t{-1});  // static_cast<std::size_t>(-1) == SIZE_MAX
  try {
    m.get_size("k", 0, std::numeric_limits<std::size_t>::max());
    FAIL() << "-1 accepted as a size";
  } catch (const ParamError& e) {
    EXPECT_STREQ(e.what(), "cfg.yaml: tdorc_filter.ros__parameters.k: must be in [0, 18446744073709551615], got -1");
  }
  EXPECT_THROW(m.get_integer<uint32_t>("k", 0u, 5000u), ParamError);
  EXPECT_THROW(m.get_integer<uint64_t>("k", 0u, std::numeric_limits<uint64_t>::max()), ParamError);
  m.set("k", int64_t{5000});
  EXPECT_EQ(m.get_integer<uint32_t>("k", 0u, 5000u), 5000u);
  m.set("k", (int64_t{1} << 32) + 10);  // would wrap to 10 as a uint32_t
  EXPECT_THROW(m.get_integer<uint32_t>("k", 0u, std::numeric_limits<uint32_t>::max()), ParamError);
  EXPECT_EQ(m.get_size("k", 0, std::numeric_limits<std::size_t>::max()), (std::size_t{1} << 32) + 10);
  m.set("k", std::numeric_limits<int64_t>::max());
  EXPECT_EQ(m.get_integer<uint64_t>("k", 0u, std::numeric_limits<uint64_t>::max()),
            uint64_t{std::numeric_limits<int64_t>::max()});
}

TEST(IntegerParameters, Int64BoundsAreExact) {
  ParamMap m = ints();
  const int64_t max = std::numeric_limits<int64_t>::max(), min = std::numeric_limits<int64_t>::min();
  m.set("k", max);
  EXPECT_EQ(m.get_int64("k", min, max), max);
  EXPECT_THROW(m.get_int64("k", min, max - 1), ParamError);
  m.set("k", min);
  EXPECT_EQ(m.get_int64("k", min, max), min);
  EXPECT_THROW(m.get_int64("k", min + 1, max), ParamError);
}

TEST(IntegerParameters, ADoubleOrAStringIsNotAnInteger) {
  ParamMap m = ints();
  m.set("k", 10.0);  // a map built in code (tests, command-line overrides) can hold one
  try {
    m.get_int("k", 0, 100);
    FAIL() << "10.0 accepted as an integer";
  } catch (const ParamError& e) {
    EXPECT_STREQ(e.what(), "cfg.yaml: tdorc_filter.ros__parameters.k: expected integer, got double");
  }
  m.set("k", std::string("10"));
  try {
    m.get_size("k", 0, 100);
    FAIL() << "\"10\" accepted as an integer";
  } catch (const ParamError& e) {
    EXPECT_STREQ(e.what(), "cfg.yaml: tdorc_filter.ros__parameters.k: expected integer, got string");
  }
  EXPECT_THROW(m.get_int("missing", 0, 1), ParamError);
}

TEST(IntegerParameters, AnEmptyRangeIsTheCallersBug) {
  ParamMap m = ints();
  EXPECT_THROW(m.get_int("k", 5, 2), std::logic_error);
}

TEST(IntegerParameters, FromAFileTheErrorNamesTheFileThatSetTheValue) {
  // 2^32 + 10 in the file: loaded as the integer it is, rejected by the read.
  auto p = load_node_parameters_from_string("tdorc_filter:\n  ros__parameters:\n    window: 4294967306\n",
                                            "config/x.yaml", "tdorc_filter", defaults());
  try {
    p.get_int("window", 2, 100000);
    FAIL();
  } catch (const ParamError& e) {
    EXPECT_STREQ(e.what(), "config/x.yaml: tdorc_filter.ros__parameters.window: must be in [2, 100000], got 4294967306");
  }
  // Past int64 YAML's integer is read as a double: rejected when the file is loaded.
  const auto msg = error_of("tdorc_filter:\n  ros__parameters:\n    window: 99999999999999999999\n");
  EXPECT_NE(msg.find("window: expected integer, got double"), std::string::npos) << msg;
  // A double for an integer: rejected at load as well, not truncated.
  const auto msg2 = error_of("tdorc_filter:\n  ros__parameters:\n    window: 10.5\n");
  EXPECT_NE(msg2.find("window: expected integer, got double"), std::string::npos) << msg2;
}

// The helper the node packages' tests use: it tells a read that narrows before
// it checks (the defect) from one that checks first.
TEST(IntegerParameters, WrappedIntegersTellAnUncheckedNarrowingFromACheckedRead) {
  ParamMap d("n", "defaults");
  d.set("window", int64_t{10});
  d.set("gain", 1.5);
  auto unchecked = [](const ParamMap& m) {
    const int window = static_cast<int>(std::get<int64_t>(m.values().at("window")));  // the old pattern
    if (window < 1 || window > 100) throw m.error("window", "must be in [1, 100], got " + std::to_string(window));
  };
  auto checked = [](const ParamMap& m) { (void)m.get_int("window", 1, 100); };
  const auto before = tactile_common::wrapped_integers(d, unchecked);
  ASSERT_EQ(before.size(), 1u);  // only the integer
  EXPECT_EQ(before.at("window").value, 4294967306);
  EXPECT_EQ(before.at("window").error, "");
  EXPECT_FALSE(before.at("window").rejected_as_given());
  const auto after = tactile_common::wrapped_integers(d, checked);
  EXPECT_EQ(after.at("window").error, "defaults: n.ros__parameters.window: must be in [1, 100], got 4294967306");
  EXPECT_TRUE(after.at("window").rejected_as_given());
}

// ParamInfo: kept beside the value (and through a copy, as load_node_parameters copies the
// defaults); ranges print as validate() messages do and exclude open ends.
TEST(ParamInfo, RangesPrintAndContainAsDescribed) {
  using tactile_common::ParamRange;
  EXPECT_EQ(tactile_common::closed(2, 100000).text(), "[2, 100000]");
  EXPECT_EQ(tactile_common::positive().text(), "(0, inf)");
  EXPECT_EQ(tactile_common::at_least(0.5).text(), "[0.5, inf)");
  EXPECT_EQ((ParamRange{0.0, 1.0, false, true}).text(), "[0, 1)");
  EXPECT_FALSE(tactile_common::positive().contains(0.0));
  EXPECT_TRUE(tactile_common::positive().contains(1e-300));
  EXPECT_FALSE(tactile_common::positive().contains(std::numeric_limits<double>::infinity()));
  EXPECT_FALSE(tactile_common::positive().contains(std::numeric_limits<double>::quiet_NaN()));
  EXPECT_TRUE(tactile_common::closed(2, 5).contains(5));
  EXPECT_FALSE((ParamRange{0.0, 1.0, false, true}).contains(1.0));

  tactile_common::ParamMap m("n", "defaults");
  m.set("gain", 1.0, {"controller gain", "1/s", tactile_common::positive(), true});
  m.set("frame", std::string("base"));
  const tactile_common::ParamMap copy = m;
  ASSERT_NE(copy.info("gain"), nullptr);
  EXPECT_EQ(copy.info("gain")->unit, "1/s");
  EXPECT_TRUE(copy.info("gain")->live);
  EXPECT_EQ(copy.info("frame"), nullptr);
  EXPECT_EQ(tactile_common::undescribed(copy), std::vector<std::string>{"frame"});
  EXPECT_THROW(m.set("bad", 1.0, {"empty", "", tactile_common::closed(2, 1), false}), std::logic_error);
}

// Where a value comes from (issue 33 item 4): the last argument of a ParamInfo, kept with it,
// printed as `tactile params` and `ros2 param describe` show it; without it a key is "unset".
TEST(ParamInfo, SourceIsKeptAndPrintsWithItsEvidence) {
  using tactile_common::ParamSource;
  tactile_common::ParamMap m("n", "defaults");
  m.set("window", int64_t{100}, {"n", "samples", tactile_common::closed(2, 1000), false,
                                 tactile_common::paper("000 eq. 6-7, n = 100")});
  m.set("frame", std::string("odom"), {"frame", "", {}, false, tactile_common::choice()});
  m.set("hold", 0.1, {"hold", "", {}, false, tactile_common::tuned("docs/tuning/x.md Round 4: 251 -> 269")});
  m.set("old", 1.0, {"not classified yet", "", {}, false});
  const tactile_common::ParamMap copy = m;
  EXPECT_EQ(copy.info("window")->source.kind, ParamSource::kPaper);
  EXPECT_EQ(copy.info("window")->source.evidence, "000 eq. 6-7, n = 100");
  EXPECT_EQ(copy.info("window")->source.text(), "paper: 000 eq. 6-7, n = 100");
  EXPECT_EQ(copy.info("frame")->source.text(), "choice");
  EXPECT_EQ(copy.info("hold")->source.text(), "tuned: docs/tuning/x.md Round 4: 251 -> 269");
  EXPECT_EQ(copy.info("old")->source.kind, ParamSource::kUnset);
  EXPECT_EQ(copy.info("old")->source.text(), "");
  EXPECT_STREQ(tactile_common::to_string(ParamSource::kTuned), "tuned");
  EXPECT_STREQ(tactile_common::to_string(ParamSource::kUnset), "unset");
}

// Integer-valued bounds print exactly, as the integer a get_int() range or an IntegerRange
// descriptor holds: INT_MAX is "2147483647", not the stream's six digits "2.14748e+09"
// (ros2 param describe of whisker_driver's baud showed that, and a refused value's reason
// "must be in [1, 2.14748e+09]"). Other bounds keep the short form.
TEST(ParamInfo, IntegerBoundsPrintExactly) {
  using tactile_common::ParamRange;
  EXPECT_EQ(tactile_common::closed(1, std::numeric_limits<int>::max()).text(), "[1, 2147483647]");
  EXPECT_EQ(tactile_common::closed(0, 1e6).text(), "[0, 1000000]");
  EXPECT_EQ(tactile_common::closed(std::numeric_limits<int>::min(), -1e7).text(), "[-2147483648, -10000000]");
  // 2^53 + 2: integer-valued doubles beyond 2^53 are still exact integers.
  EXPECT_EQ(tactile_common::at_least(9007199254740994.0).text(), "[9007199254740994, inf)");
  // INT64_MIN is a double exactly; INT64_MAX is not (it rounds to 2^63, printed so it reads back).
  EXPECT_EQ(tactile_common::closed(static_cast<double>(std::numeric_limits<int64_t>::min()), 0).text(),
            "[-9223372036854775808, 0]");
  EXPECT_EQ(tactile_common::closed(0, static_cast<double>(std::numeric_limits<int64_t>::max())).text(),
            "[0, 9.2233720368547758e+18]");
  EXPECT_EQ((ParamRange{-0.0, 1.0, true, false}).text(), "(0, 1]");
  EXPECT_EQ(tactile_common::at_least(1e-6).text(), "[1e-06, inf)");
  EXPECT_EQ((ParamRange{0.05, 1.5, true, true}).text(), "(0.05, 1.5)");
}

// range_leaks finds a described range narrower than what params_from accepts:
// a value just outside it that params_from takes.
TEST(ParamInfo, RangeLeaksFindsADescribedRangeNarrowerThanTheCheck) {
  tactile_common::ParamMap d("n", "defaults");
  d.set("window", int64_t{5}, {"samples", "samples", tactile_common::closed(2, 10), false});
  d.set("gain", 1.0, {"gain", "", tactile_common::positive(), false});
  const auto checked = [](const tactile_common::ParamMap& m) {
    m.get_int("window", 1, 10);  // takes 1: the description's 2 is too narrow
    if (!(m.get_double("gain") > 0.0)) throw m.error("gain", "must be > 0");
  };
  const auto leaks = tactile_common::range_leaks(d, checked);
  ASSERT_EQ(leaks.size(), 1u);
  EXPECT_EQ(leaks[0].key, "window");
  EXPECT_EQ(leaks[0].value, 1.0);
}

// infinities_accepted finds an unbounded described range whose infinite end params_from
// takes ("> 0" checked without isfinite): (0, inf) means every finite value. A closed
// infinite end, (0, inf], takes infinity on purpose (inf = never) and is not reported.
TEST(ParamInfo, InfinitiesAcceptedFindsAnInfiniteEndTheCheckTakes) {
  const double inf = std::numeric_limits<double>::infinity();
  tactile_common::ParamMap d("n", "defaults");
  d.set("age", 0.2, {"age", "s", tactile_common::positive(), false});
  d.set("gain", 1.0, {"gain", "", tactile_common::positive(), false});
  d.set("offset", 0.0, {"offset", "m", tactile_common::ParamRange{-inf, inf, true, true}, false});  // (-inf, inf)
  d.set("timeout", 0.2, {"timeout; inf: never", "s", tactile_common::ParamRange{0.0, inf, true, false}, false});
  const auto checked = [](const tactile_common::ParamMap& m) {
    if (!(m.get_double("timeout") > 0.0)) throw m.error("timeout", "must be > 0");  // takes inf, as described
    if (!(m.get_double("age") > 0.0)) throw m.error("age", "must be > 0");  // takes inf
    const double gain = m.get_double("gain");
    if (!(std::isfinite(gain) && gain > 0.0)) throw m.error("gain", "must be finite and > 0");
    if (!std::isfinite(m.get_double("offset"))) throw m.error("offset", "must be finite");
  };
  const auto accepted = tactile_common::infinities_accepted(d, checked);
  ASSERT_EQ(accepted.size(), 1u);
  EXPECT_EQ(accepted[0].key, "age");
  EXPECT_EQ(accepted[0].value, std::numeric_limits<double>::infinity());
}

// Parameter profiles (config/profiles/): a file naming only the nodes it changes.
namespace {
std::filesystem::path write_profile(const std::string& text) {
  const auto path = std::filesystem::temp_directory_path() / ("profile_" + std::to_string(::getpid()) + ".yaml");
  std::ofstream(path) << text;
  return path;
}
}  // namespace

TEST(ParameterProfiles, OverlayHoldsOnlyTheKeysTheProfileChangesForTheNode) {
  const auto path = write_profile(
      "/**/tdorc_filter:\n  ros__parameters: {window: 50, contact_threshold: 20.0}\n"
      "/**/tactile_depth:\n  ros__parameters: {other: 1}\n");
  const ParamMap o = tactile_common::load_profile_overlay(path.string(), "/whisker/left/tdorc_filter", defaults());
  // window changes; contact_threshold is set to the value the node has: no change.
  ASSERT_EQ(o.values().size(), 1u);
  EXPECT_EQ(o.get_int64("window", 0, 1000), 50);
  EXPECT_EQ(o.source(), path.string());
  ParamMap merged = defaults();
  merged.merge_from(o);
  EXPECT_EQ(merged.get_int64("window", 0, 1000), 50);
  EXPECT_EQ(merged.origin("window"), path.string());
  std::filesystem::remove(path);
}

TEST(ParameterProfiles, ANodeTheProfileDoesNotNameGetsNothing) {
  const auto path = write_profile("/**/tactile_depth:\n  ros__parameters: {kf.q: 0.5}\n");
  EXPECT_TRUE(tactile_common::load_profile_overlay(path.string(), "tdorc_filter", defaults()).values().empty());
  std::filesystem::remove(path);
}

TEST(ParameterProfiles, ATypoOrAMissingProfileIsAnErrorNamingTheFile) {
  const auto path = write_profile("/**/tdorc_filter:\n  ros__parameters: {windw: 50}\n");
  try {
    tactile_common::load_profile_overlay(path.string(), "tdorc_filter", defaults());
    ADD_FAILURE() << "a misspelt key accepted";
  } catch (const ParamError& e) {
    EXPECT_NE(std::string(e.what()).find(path.string()), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("windw"), std::string::npos) << e.what();
  }
  std::filesystem::remove(path);
  EXPECT_THROW(tactile_common::load_profile_overlay(path.string(), "tdorc_filter", defaults()), ParamError);
}
