// SPDX-License-Identifier: Apache-2.0
// The DDS domain a program joins (panoptes/dds/domain.h): parsing and choosing, without DDS; and
// that a Bus refuses a bad $PANOPTES_DOMAIN before it creates a participant.
#include <cstdlib>
#include <optional>
#include <string>
#include <string_view>

#include <gtest/gtest.h>

#include "panoptes/dds/bus.h"
#include "panoptes/dds/domain.h"
#include "panoptes/dds/domain_option.h"

namespace panoptes::dds {
namespace {

// The message a DomainError carries, or "" when `call` does not throw one.
template <class Call>
std::string domain_error_of(Call call) {
  try {
    call();
  } catch (const DomainError& error) {
    return error.what();
  }
  return "";
}

TEST(Domain, ParsesEveryIdOfTheRange) {
  EXPECT_EQ(parse_domain("0", "PANOPTES_DOMAIN"), 0);
  EXPECT_EQ(parse_domain("7", "PANOPTES_DOMAIN"), 7);
  EXPECT_EQ(parse_domain("042", "PANOPTES_DOMAIN"), 42);
  EXPECT_EQ(parse_domain("0007", "PANOPTES_DOMAIN"), 7);
  EXPECT_EQ(parse_domain("232", "PANOPTES_DOMAIN"), kMaxDomainId);
}

TEST(Domain, RejectsWhatIsNotAnIdOfTheRangeNamingSourceAndValue) {
  for (const std::string_view bad : {"abc", "300", "233", "-1", "+5", " 5", "5 ", "5x", "0x10", "1e2", "",
                                     "99999999999999999999", "2320"}) {
    SCOPED_TRACE(std::string(bad));
    const std::string what = domain_error_of([&] { parse_domain(bad, "PANOPTES_DOMAIN"); });
    EXPECT_EQ(what, "PANOPTES_DOMAIN=" + std::string(bad) + ": not a DDS domain id (an integer 0..232)");
  }
}

TEST(Domain, IsAConfigErrorSoProgramsExitTwo) {
  EXPECT_THROW(parse_domain("abc", "PANOPTES_DOMAIN"), ConfigError);
}

TEST(Domain, ExplicitRequestWinsOverTheVariableAndIsChecked) {
  EXPECT_EQ(choose_domain(5, "abc"), 5);
  EXPECT_EQ(choose_domain(232, std::nullopt), 232);
  EXPECT_EQ(domain_error_of([] { choose_domain(300, std::nullopt); }),
            "domain=300: not a DDS domain id (an integer 0..232)");
}

TEST(Domain, VariableUnsetOrEmptyMeansZero) {
  EXPECT_EQ(choose_domain(-1, std::nullopt), 0);
  EXPECT_EQ(choose_domain(-1, ""), 0);
  EXPECT_EQ(choose_domain(-1, "17"), 17);
  EXPECT_NE(domain_error_of([] { choose_domain(-1, "abc"); }).find("PANOPTES_DOMAIN=abc"), std::string::npos);
  EXPECT_NE(domain_error_of([] { choose_domain(-1, "300"); }).find("PANOPTES_DOMAIN=300"), std::string::npos);
}

// Restores $PANOPTES_DOMAIN when a test that sets it ends.
class DomainVariable {
 public:
  explicit DomainVariable(const char* value) {
    if (const char* old = std::getenv(kDomainVariable)) old_ = old;
    ::setenv(kDomainVariable, value, 1);
  }
  ~DomainVariable() {
    if (old_) {
      ::setenv(kDomainVariable, old_->c_str(), 1);
    } else {
      ::unsetenv(kDomainVariable);
    }
  }
  DomainVariable(const DomainVariable&) = delete;
  DomainVariable& operator=(const DomainVariable&) = delete;

 private:
  std::optional<std::string> old_;
};

TEST(Domain, ResolveReadsTheVariable) {
  {
    const DomainVariable variable("12");
    EXPECT_EQ(resolve_domain(), 12);
    EXPECT_EQ(resolve_domain(3), 3);
  }
  const DomainVariable variable("abc");
  EXPECT_EQ(domain_error_of([] { resolve_domain(); }),
            "PANOPTES_DOMAIN=abc: not a DDS domain id (an integer 0..232)");
}

// --domain (issue 34 item 10): a good id becomes $PANOPTES_DOMAIN, so every bus opened later joins
// it; a typo is refused naming the flag and leaves the variable as it was, never domain 0.
TEST(Domain, FlagSetsTheVariableOrRefuses) {
  const DomainVariable variable("7");
  CLI::App app{"test"};
  add_domain_option(app);
  const char* good[] = {"program", "--domain", "89"};
  app.parse(3, good);
  EXPECT_EQ(resolve_domain(), 89);
  for (const char* bad : {"8x9", "-1", "233", ""}) {
    ::setenv(kDomainVariable, "7", 1);
    CLI::App again{"test"};
    add_domain_option(again);
    const char* argv[] = {"program", "--domain", bad};
    EXPECT_EQ(domain_error_of([&] { again.parse(3, argv); }),
              std::string("--domain=") + bad + ": not a DDS domain id (an integer 0..232)")
        << bad;
    EXPECT_EQ(resolve_domain(), 7) << bad;
  }
}

// Before the fix the bus read the variable with atoi: "abc" joined domain 0 and 300 made Fast DDS
// exit the process. Both are refused before a participant exists.
TEST(Domain, BusRefusesABadVariable) {
  for (const char* bad : {"abc", "300"}) {
    const DomainVariable variable(bad);
    const std::string what = domain_error_of([] { Bus bus; });
    EXPECT_EQ(what, std::string("PANOPTES_DOMAIN=") + bad + ": not a DDS domain id (an integer 0..232)");
  }
  BusOptions options;
  options.domain_id = 233;
  EXPECT_EQ(domain_error_of([&] { Bus bus(options); }),
            "domain=233: not a DDS domain id (an integer 0..232)");
}

}  // namespace
}  // namespace panoptes::dds
