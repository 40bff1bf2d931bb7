// SPDX-License-Identifier: Apache-2.0
// DDS Security's file checks (panoptes/dds/security.h): every bad file is named with its reason
// before a participant is created, and a profile that requires security refuses to start without
// it. The cryptographic checks (signatures, chain, expiry, revocation) are Fast DDS's, exercised
// by tests/integration/test_security.sh.
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

#include <gtest/gtest.h>

#include "panoptes/dds/bus.h"
#include "panoptes/dds/security.h"

namespace panoptes::dds {
namespace {

namespace fs = std::filesystem;

constexpr const char* kCertificate = "-----BEGIN CERTIFICATE-----\nMIIB\n-----END CERTIFICATE-----\n";

std::string signed_document(const std::string& xml) {
  return "MIME-Version: 1.0\nContent-Type: multipart/signed; protocol=\"application/x-pkcs7-signature\"; "
         "boundary=\"B\"\n\n--B\nContent-Type: text/plain\n\n" +
         xml + "\n--B\nContent-Type: application/x-pkcs7-signature; name=\"smime.p7s\"\n\nMIIG\n--B--\n";
}

void write(const fs::path& path, const std::string& content) {
  fs::create_directories(path.parent_path());
  std::ofstream(path) << content;
}

// A studio directory with well-formed (not cryptographically valid) files for identity "cam0".
class SecurityFilesTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("panoptes-security-test-" + std::to_string(getpid()));
    write(dir_ / "identity_ca.pem", kCertificate);
    write(dir_ / "permissions_ca.pem", kCertificate);
    write(dir_ / "identity_crl.pem", "-----BEGIN X509 CRL-----\nMIIB\n-----END X509 CRL-----\n");
    write(dir_ / "governance.p7s",
          signed_document(
              "<?xml version=\"1.0\"?><dds><domain_access_rules><domain_rule/></domain_access_rules></dds>"));
    write(node() / "cert.pem", kCertificate);
    write(node() / "key.pem", "-----BEGIN EC PRIVATE KEY-----\nMHc\n-----END EC PRIVATE KEY-----\n");
    write(
        node() / "permissions.p7s",
        signed_document("<dds><permissions><grant name=\"cam0\"><subject_name>CN=cam0</subject_name></grant>"
                        "</permissions></dds>"));
  }
  void TearDown() override { fs::remove_all(dir_); }
  fs::path node() const { return dir_ / "identities" / "cam0"; }
  SecurityFiles files() const { return *resolve_security_files({dir_, "cam0"}); }

  // The message of the SecurityError that check_security_files throws; "" if none.
  std::string check_error() const {
    try {
      check_security_files(files());
    } catch (const SecurityError& error) {
      return error.what();
    }
    return "";
  }

  fs::path dir_;
};

TEST_F(SecurityFilesTest, WellFormedFilesPassAndBecomeTheBuiltinPluginProperties) {
  EXPECT_EQ(check_error(), "");
  const auto properties = security_properties(files());
  const auto value_of = [&](const std::string& name) {
    for (const auto& [key, value] : properties)
      if (key == name) return value;
    return std::string("(missing)");
  };
  EXPECT_EQ(value_of("dds.sec.auth.plugin"), "builtin.PKI-DH");
  EXPECT_EQ(value_of("dds.sec.access.plugin"), "builtin.Access-Permissions");
  EXPECT_EQ(value_of("dds.sec.crypto.plugin"), "builtin.AES-GCM-GMAC");
  EXPECT_EQ(value_of("dds.sec.auth.builtin.PKI-DH.preferred_key_agreement"), "ECDH");
  EXPECT_EQ(value_of("dds.sec.auth.builtin.PKI-DH.identity_certificate"),
            "file://" + (node() / "cert.pem").string());
  EXPECT_EQ(value_of("dds.sec.auth.builtin.PKI-DH.identity_crl"),
            "file://" + (dir_ / "identity_crl.pem").string());
  EXPECT_EQ(value_of("dds.sec.access.builtin.Access-Permissions.permissions"),
            "file://" + (node() / "permissions.p7s").string());
}

TEST_F(SecurityFilesTest, EachBadFileIsNamedWithItsReason) {
  fs::remove(node() / "key.pem");
  EXPECT_EQ(check_error(), (node() / "key.pem").string() + ": private key: no such file");
  write(node() / "key.pem",
        "-----BEGIN ENCRYPTED PRIVATE KEY-----\nMII\n-----END ENCRYPTED PRIVATE KEY-----\n");
  EXPECT_NE(check_error().find("key.pem: private key: encrypted"), std::string::npos) << check_error();
  write(node() / "key.pem", "-----BEGIN EC PRIVATE KEY-----\nMHc\n-----END EC PRIVATE KEY-----\n");

  write(node() / "cert.pem", "hello");
  EXPECT_EQ(check_error(), (node() / "cert.pem").string() +
                               ": identity certificate: no PEM block '-----BEGIN CERTIFICATE-----'");
  write(node() / "cert.pem", kCertificate);

  write(dir_ / "governance.p7s",
        signed_document("<dds><domain_access_rules><domain_rule></domain_rul></dds>"));
  EXPECT_NE(check_error().find("governance.p7s: governance: the XML does not parse"), std::string::npos)
      << check_error();
  write(dir_ / "governance.p7s", "<dds><domain_access_rules><domain_rule/></domain_access_rules></dds>");
  EXPECT_NE(check_error().find("governance.p7s: governance: not an S/MIME signed document"),
            std::string::npos);
  write(dir_ / "governance.p7s", signed_document("<dds><domain_access_rules/></dds>"));
  EXPECT_NE(check_error().find("no <dds><domain_access_rules><domain_rule>"), std::string::npos)
      << check_error();
  write(dir_ / "governance.p7s",
        signed_document("<dds><domain_access_rules><domain_rule/></domain_access_rules></dds>"));

  write(node() / "permissions.p7s", signed_document("<dds><permissions/></dds>"));
  EXPECT_NE(check_error().find("permissions.p7s: permissions: no <dds><permissions><grant>"),
            std::string::npos);
  fs::remove(node() / "permissions.p7s");
  fs::create_directory(node() / "permissions.p7s");
  EXPECT_NE(check_error().find("permissions.p7s: permissions: not a regular file"), std::string::npos);
}

TEST_F(SecurityFilesTest, AnIdentityWithoutItsDirectoryIsNamed) {
  const SecurityFiles other = *resolve_security_files({dir_, "cam9"});
  try {
    check_security_files(other);
    FAIL() << "an identity without a directory passed";
  } catch (const SecurityError& error) {
    EXPECT_EQ(std::string(error.what()),
              (dir_ / "identities" / "cam9").string() +
                  ": identity: no such directory (panoptes-security issue <dir> <role> <name>)");
  }
}

TEST_F(SecurityFilesTest, AnUnreadableFileIsNamed) {
  if (geteuid() == 0) GTEST_SKIP() << "root reads every file";
  fs::permissions(node() / "key.pem", fs::perms::none);
  EXPECT_NE(check_error().find("key.pem: private key: cannot be read"), std::string::npos) << check_error();
}

TEST(SecurityOptions, DirectoryAndIdentityGoTogether) {
  ::unsetenv("PANOPTES_SECURITY_DIR");
  ::unsetenv("PANOPTES_SECURITY_IDENTITY");
  EXPECT_FALSE(resolve_security_files({}).has_value());
  EXPECT_THROW(resolve_security_files({"/tmp", ""}), SecurityError);
  EXPECT_THROW(resolve_security_files({"", "cam0"}), SecurityError);
  EXPECT_THROW(resolve_security_files({"/nonexistent/studio", "cam0"}), SecurityError);
  EXPECT_THROW(resolve_security_files({"/tmp", "../etc"}), SecurityError);
  ::setenv("PANOPTES_SECURITY_DIR", "/tmp", 1);
  ::setenv("PANOPTES_SECURITY_IDENTITY", "cam7", 1);
  const auto files = resolve_security_files({});
  ASSERT_TRUE(files.has_value());
  EXPECT_EQ(files->certificate, fs::path("/tmp/identities/cam7/cert.pem"));
  ::unsetenv("PANOPTES_SECURITY_DIR");
  ::unsetenv("PANOPTES_SECURITY_IDENTITY");
}

// deploy/dds/secure.xml requires security: without it the Bus refuses before creating a participant
// (so this test joins no network), and never falls back to an unsecured one.
TEST(SecurityOptions, TheSecureProfileRefusesToStartUnsecured) {
  ::unsetenv("PANOPTES_SECURITY_DIR");
  ::unsetenv("PANOPTES_SECURITY_IDENTITY");
  BusOptions options;
  options.profile_file = fs::path(PANOPTES_SOURCE_DIR) / "deploy/dds/secure.xml";
  try {
    Bus bus(options);
    FAIL() << "an unsecured participant was created with the secure profile";
  } catch (const SecurityError& error) {
    EXPECT_NE(std::string(error.what()).find("requires DDS Security"), std::string::npos) << error.what();
  }
}

// The domains a studio's documents cover, read as Fast DDS reads them: a node on a domain its
// governance does not cover would join without the governance's protection (Fast DDS 2.9 creates
// the participant and then refuses every topic), so it is refused before joining, naming the domain.
TEST_F(SecurityFilesTest, ADomainTheDocumentsDoNotCoverIsRefusedBeforeJoining) {
  const auto domain_error = [&](int domain) -> std::string {
    try {
      check_security_domain(files(), domain);
    } catch (const SecurityError& error) {
      return error.what();
    }
    return "";
  };
  const auto governance = [&](const std::string& domains) {
    write(dir_ / "governance.p7s",
          signed_document("<dds><domain_access_rules><domain_rule><domains>" + domains +
                          "</domains></domain_rule></domain_access_rules></dds>"));
  };
  const auto permissions = [&](const std::string& domains) {
    write(node() / "permissions.p7s",
          signed_document("<dds><permissions><grant name=\"cam0\"><subject_name>CN=cam0</subject_name>"
                          "<allow_rule><domains>" +
                          domains + "</domains></allow_rule></grant></permissions></dds>"));
  };
  governance("<id_range><min>0</min><max>230</max></id_range>");
  permissions("<id_range><min>0</min><max>230</max></id_range>");
  EXPECT_EQ(domain_error(0), "");
  EXPECT_EQ(domain_error(230), "");
  EXPECT_EQ(domain_error(231),
            (dir_ / "governance.p7s").string() +
                ": governance: no domain_rule covers DDS domain 231 (it covers 0..230; Fast "
                "DDS would join without the governance's protection). A studio made by "
                "panoptes-security covers domains 0..230 (docs/security.md, \"Domains\")");
  // <id>, a range from 0 without <min>, and <min> alone (Fast DDS reads it as that one id).
  governance("<id>7</id><id_range><max>3</max></id_range><id_range><min>20</min></id_range>");
  for (const int covered : {0, 3, 7, 20}) EXPECT_EQ(domain_error(covered), "") << covered;
  for (const int outside : {4, 8, 21, 232})
    EXPECT_NE(domain_error(outside).find("governance: no domain_rule covers DDS domain " +
                                         std::to_string(outside) + " (it covers 7, 0..3, 20;"),
              std::string::npos)
        << domain_error(outside);
  governance("<id_range><min>0</min><max>232</max></id_range>");
  EXPECT_NE(
      domain_error(232).find("permissions.p7s: permissions: no allow_rule covers DDS domain 232 (it covers "
                             "0..230; Fast DDS would refuse every topic)"),
      std::string::npos)
      << domain_error(232);
  permissions("");
  EXPECT_NE(domain_error(0).find("no allow_rule covers DDS domain 0 (it covers none;"), std::string::npos)
      << domain_error(0);
}

}  // namespace
}  // namespace panoptes::dds
