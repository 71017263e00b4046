// rover::cli::ArgParser: option syntaxes, flags, one-line usage errors that name the option,
// number parsing and ranges, positionals, and the --help text.
#include <doctest/doctest.h>

#include <cstdint>
#include <string>
#include <vector>

#include "server/cli/arg_parser.hpp"

using rover::cli::ArgParser;
using rover::cli::UsageError;

namespace {

// A parser with one option of each kind, as the subcommands build them.
ArgParser makeParser() {
  ArgParser p("demo", "A demo command.");
  p.option("rows", "N", "60", "Grid rows.");
  p.option("cell", "M", "1.0", "Cell size in metres.");
  p.option("name", "TEXT", "", "A name without a default.");
  p.option("costs", "V,V,...", "", "Some numbers.");
  p.flag("json", "Print JSON.");
  p.flag("verbose", "Say more.");
  return p;
}

// The message of the UsageError thrown by fn ("" if none was thrown).
template <class Fn>
std::string usageMessage(Fn&& fn) {
  try {
    fn();
  } catch (const UsageError& e) {
    return e.what();
  }
  return "";
}

bool contains(const std::string& haystack, const std::string& needle) {
  return haystack.find(needle) != std::string::npos;
}

}  // namespace

TEST_CASE("ArgParser reads --name value") {
  ArgParser p = makeParser();
  REQUIRE(p.parse({"--rows", "12", "--name", "alpha"}));
  CHECK(p.has("rows"));
  CHECK(p.has("name"));
  CHECK_FALSE(p.has("cell"));
  CHECK(p.str("rows", "") == "12");
  CHECK(p.str("name", "") == "alpha");
  CHECK(p.integer("rows", 0, 0, 100) == 12);
  CHECK(p.positionals().empty());
}

TEST_CASE("ArgParser reads --name=value, including values with '=' and empty values") {
  ArgParser p = makeParser();
  REQUIRE(p.parse({"--rows=7", "--name=a=b", "--costs="}));
  CHECK(p.integer("rows", 0, 0, 100) == 7);
  CHECK(p.str("name", "") == "a=b");
  CHECK(p.has("costs"));
  CHECK(p.str("costs", "fallback") == "");
}

TEST_CASE("ArgParser: a value that looks like an option is taken as the value") {
  ArgParser p = makeParser();
  REQUIRE(p.parse({"--name", "--json"}));
  CHECK(p.str("name", "") == "--json");
  CHECK_FALSE(p.isSet("json"));
}

TEST_CASE("ArgParser: the last occurrence of an option wins") {
  ArgParser p = makeParser();
  REQUIRE(p.parse({"--rows", "1", "--rows=2"}));
  CHECK(p.integer("rows", 0, 0, 100) == 2);
}

TEST_CASE("ArgParser: fallbacks are returned for options that were not given") {
  ArgParser p = makeParser();
  REQUIRE(p.parse({}));
  CHECK(p.str("name", "dflt") == "dflt");
  CHECK(p.integer("rows", 60, 2, 4096) == 60);
  CHECK(p.real("cell", 1.5, 0.0, 10.0) == doctest::Approx(1.5));
  CHECK(p.realList("costs").empty());
  CHECK_FALSE(p.isSet("json"));
  // The fallback is not range-checked: it is the command's own default.
  CHECK(p.integer("rows", -5, 0, 10) == -5);
}

TEST_CASE("ArgParser flags") {
  ArgParser p = makeParser();
  REQUIRE(p.parse({"--json"}));
  CHECK(p.isSet("json"));
  CHECK(p.has("json"));
  CHECK_FALSE(p.isSet("verbose"));

  ArgParser both = makeParser();
  REQUIRE(both.parse({"--verbose", "--rows", "3", "--json"}));
  CHECK(both.isSet("json"));
  CHECK(both.isSet("verbose"));
  CHECK(both.integer("rows", 0, 0, 10) == 3);
}

TEST_CASE("ArgParser: a flag given a value is an error naming the flag") {
  ArgParser p = makeParser();
  CHECK_THROWS_WITH_AS(p.parse({"--json=1"}), "option --json takes no value", UsageError);
  ArgParser q = makeParser();
  CHECK_THROWS_AS(q.parse({"--verbose="}), UsageError);
  // A separate word after a flag is not its value: with no positionals declared it is unexpected.
  ArgParser r = makeParser();
  CHECK_THROWS_WITH_AS(r.parse({"--json", "1"}), "unexpected argument '1'", UsageError);
}

TEST_CASE("ArgParser: an unknown option is an error naming it") {
  ArgParser p = makeParser();
  CHECK_THROWS_WITH_AS(p.parse({"--foo"}), "unknown option --foo (see --help)", UsageError);
  ArgParser q = makeParser();
  CHECK_THROWS_WITH_AS(q.parse({"--rows", "3", "--foo=3"}), "unknown option --foo (see --help)",
                       UsageError);
  // Option names are exact: no prefix matching, no case folding.
  ArgParser r = makeParser();
  CHECK_THROWS_WITH_AS(r.parse({"--row", "3"}), "unknown option --row (see --help)", UsageError);
  ArgParser s = makeParser();
  CHECK_THROWS_WITH_AS(s.parse({"--JSON"}), "unknown option --JSON (see --help)", UsageError);
}

TEST_CASE("ArgParser: an option without its value is an error naming it") {
  ArgParser p = makeParser();
  CHECK_THROWS_WITH_AS(p.parse({"--rows"}), "option --rows needs a value", UsageError);
  ArgParser q = makeParser();
  CHECK_THROWS_WITH_AS(q.parse({"--json", "--name"}), "option --name needs a value", UsageError);
}

TEST_CASE("ArgParser::integer parses integers and rejects everything else, naming the option") {
  ArgParser ok = makeParser();
  REQUIRE(ok.parse({"--rows", "-42"}));
  CHECK(ok.integer("rows", 0, -100, 100) == -42);

  for (const std::string bad : {"abc", "", "12x", "1.5", "3e2", "0x", "99999999999999999999999"}) {
    CAPTURE(bad);
    ArgParser p = makeParser();
    REQUIRE(p.parse({"--rows", bad}));
    const std::string msg = usageMessage([&] { (void)p.integer("rows", 0, INT64_MIN, INT64_MAX); });
    CHECK(contains(msg, "--rows"));
    CHECK(contains(msg, "expected an integer"));
    CHECK(contains(msg, "'" + bad + "'"));
  }
}

TEST_CASE("ArgParser::integer range errors name the option and the range") {
  ArgParser p = makeParser();
  REQUIRE(p.parse({"--rows", "1"}));
  CHECK_THROWS_WITH_AS((void)p.integer("rows", 60, 2, 4096),
                       "invalid value '1' for --rows: must be in [2, 4096]", UsageError);
  ArgParser q = makeParser();
  REQUIRE(q.parse({"--rows=5000"}));
  CHECK_THROWS_WITH_AS((void)q.integer("rows", 60, 2, 4096),
                       "invalid value '5000' for --rows: must be in [2, 4096]", UsageError);
  // The bounds are inclusive.
  ArgParser lo = makeParser();
  REQUIRE(lo.parse({"--rows=2"}));
  CHECK(lo.integer("rows", 60, 2, 4096) == 2);
  ArgParser hi = makeParser();
  REQUIRE(hi.parse({"--rows=4096"}));
  CHECK(hi.integer("rows", 60, 2, 4096) == 4096);
}

TEST_CASE("ArgParser::real parses numbers and rejects everything else, naming the option") {
  ArgParser ok = makeParser();
  REQUIRE(ok.parse({"--cell", "0.25"}));
  CHECK(ok.real("cell", 1.0, 0.0, 10.0) == doctest::Approx(0.25));
  ArgParser sci = makeParser();
  REQUIRE(sci.parse({"--cell=2e-1"}));
  CHECK(sci.real("cell", 1.0, 0.0, 10.0) == doctest::Approx(0.2));

  for (const std::string bad : {"abc", "", "1.5m", "nan", "inf", "-inf", "1e999"}) {
    CAPTURE(bad);
    ArgParser p = makeParser();
    REQUIRE(p.parse({"--cell", bad}));
    const std::string msg = usageMessage([&] { (void)p.real("cell", 1.0, -1e300, 1e300); });
    CHECK(contains(msg, "--cell"));
    CHECK(contains(msg, "expected a number"));
  }
}

TEST_CASE("ArgParser::real range errors name the option and the range") {
  ArgParser p = makeParser();
  REQUIRE(p.parse({"--cell", "0"}));
  const std::string msg = usageMessage([&] { (void)p.real("cell", 1.0, 0.001, 10000.0); });
  CHECK(contains(msg, "--cell"));
  CHECK(contains(msg, "'0'"));
  CHECK(contains(msg, "must be in [0.001, 10000]"));

  ArgParser q = makeParser();
  REQUIRE(q.parse({"--cell", "0.9000001"}));
  CHECK_THROWS_AS((void)q.real("cell", 0.05, 0.0, 0.9), UsageError);
  ArgParser edge = makeParser();
  REQUIRE(edge.parse({"--cell", "0.9"}));
  CHECK(edge.real("cell", 0.05, 0.0, 0.9) == doctest::Approx(0.9));
}

TEST_CASE("ArgParser::realList parses comma-separated numbers") {
  ArgParser p = makeParser();
  REQUIRE(p.parse({"--costs", "1,2.5,-3,4e1"}));
  const std::vector<double> v = p.realList("costs");
  REQUIRE(v.size() == 4);
  CHECK(v[0] == doctest::Approx(1.0));
  CHECK(v[1] == doctest::Approx(2.5));
  CHECK(v[2] == doctest::Approx(-3.0));
  CHECK(v[3] == doctest::Approx(40.0));

  ArgParser one = makeParser();
  REQUIRE(one.parse({"--costs=7"}));
  CHECK(one.realList("costs") == std::vector<double>{7.0});

  for (const std::string bad : {"1,,2", "1,a", ",1", "1;2", "1,nan", "1, 2x"}) {
    CAPTURE(bad);
    ArgParser q = makeParser();
    REQUIRE(q.parse({"--costs", bad}));
    const std::string msg = usageMessage([&] { (void)q.realList("costs"); });
    CHECK(contains(msg, "--costs"));
    CHECK(contains(msg, "expected comma-separated numbers"));
  }
}

TEST_CASE("ArgParser positionals") {
  auto make = [] {
    ArgParser p("bench", "Benchmarks.");
    p.positional("TARGET", "coverage");
    p.option("runs", "N", "2000", "Runs per measurement.");
    return p;
  };
  SUBCASE("given, before or after options") {
    ArgParser p = make();
    REQUIRE(p.parse({"coverage", "--runs", "5"}));
    REQUIRE(p.positionals().size() == 1);
    CHECK(p.positionals()[0] == "coverage");
    CHECK(p.integer("runs", 0, 1, 100) == 5);
    ArgParser q = make();
    REQUIRE(q.parse({"--runs=5", "coverage"}));
    REQUIRE(q.positionals().size() == 1);
    CHECK(q.positionals()[0] == "coverage");
  }
  SUBCASE("missing") {
    ArgParser p = make();
    CHECK_THROWS_WITH_AS(p.parse({}), "missing argument TARGET", UsageError);
    ArgParser q = make();
    CHECK_THROWS_WITH_AS(q.parse({"--runs", "5"}), "missing argument TARGET", UsageError);
  }
  SUBCASE("unexpected") {
    ArgParser p = make();
    CHECK_THROWS_WITH_AS(p.parse({"coverage", "extra"}), "unexpected argument 'extra'", UsageError);
    ArgParser none = makeParser();
    CHECK_THROWS_WITH_AS(none.parse({"stray"}), "unexpected argument 'stray'", UsageError);
  }
  SUBCASE("--help wins over a missing positional") {
    ArgParser p = make();
    CHECK_FALSE(p.parse({"--help"}));
  }
}

TEST_CASE("ArgParser: --help and -h make parse return false") {
  ArgParser p = makeParser();
  CHECK_FALSE(p.parse({"--help"}));
  ArgParser q = makeParser();
  CHECK_FALSE(q.parse({"-h"}));
  ArgParser r = makeParser();
  CHECK_FALSE(r.parse({"--rows", "3", "--help"}));
  ArgParser s = makeParser();
  CHECK(s.parse({"--rows", "3"}));
}

TEST_CASE("ArgParser::help lists the usage, the summary and every option with its default") {
  ArgParser p("demo", "A demo command.");
  p.positional("TARGET", "What to run.");
  p.option("rows", "N", "60", "Grid rows.");
  p.option("cell", "M", "1.0", "Cell size in metres.");
  p.option("name", "TEXT", "", "A name without a default.");
  p.flag("json", "Print JSON.");
  const std::string h = p.help();

  CHECK(contains(h, "usage: roverplan demo TARGET [options]"));
  CHECK(contains(h, "A demo command."));
  CHECK(contains(h, "What to run."));
  CHECK(contains(h, "--rows N\n      Grid rows. (default: 60)\n"));
  CHECK(contains(h, "--cell M\n      Cell size in metres. (default: 1.0)\n"));
  // No default: no "(default: )" text.
  CHECK(contains(h, "--name TEXT\n      A name without a default.\n"));
  CHECK_FALSE(contains(h, "(default: )"));
  // Flags take no value and show no default.
  CHECK(contains(h, "--json\n      Print JSON.\n"));
  CHECK(contains(h, "--help"));
  // Options are listed in declaration order.
  CHECK(h.find("--rows") < h.find("--cell"));
  CHECK(h.find("--cell") < h.find("--name"));
  CHECK(h.find("--name") < h.find("--json"));
}

TEST_CASE("a trailing comma in a list is an error, like a doubled one") {
  rover::cli::ArgParser a("t", "t");
  a.option("cost-table", "V,V", "", "list");
  REQUIRE(a.parse({"--cost-table=1,2,"}));
  CHECK_THROWS_AS(a.realList("cost-table"), rover::cli::UsageError);
}
