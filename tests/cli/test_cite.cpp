// `campaign cite`'s choice of references (cli/cite.hpp): the models a store's points used select
// theirs from the one table; every reference has plain text and a well-formed BibTeX entry.
#include "cli/cite.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <sstream>
#include <string>
#include <vector>

namespace hopper::cli {
namespace {

bool has(const std::vector<std::string>& keys, const std::string& k) {
    return std::find(keys.begin(), keys.end(), k) != keys.end();
}

TEST(Cite, TheModelsThePointsUsedSelectTheirReferences) {
    engine::SceneParams verlet;  // the defaults: verlet, linear contacts, no fields
    const auto plain = cited_keys(cite_use({verlet}));
    for (const char* k : {"hopper", "kondic2014", "tang2011", "cundall1979", "swope1982",
                          "blackman2021", "kaplan1958", "lawless2003", "beverloo1961"})
        EXPECT_TRUE(has(plain, k)) << k;
    for (const char* k : {"gear1971", "hertz1882", "welford1962", "chan1979"})
        EXPECT_FALSE(has(plain, k)) << k;

    engine::SceneParams gear = verlet;
    gear.integrator.scheme = engine::Scheme::gear4;
    gear.material.normal_law = engine::NormalLaw::hertz;
    gear.fields.enabled = true;
    const CiteUse both = cite_use({verlet, gear});
    EXPECT_EQ(both.points, 2);
    EXPECT_EQ(both.gear4, 1);
    EXPECT_EQ(both.verlet, 1);
    const auto all = cited_keys(both);
    for (const char* k : {"gear1971", "swope1982", "hertz1882", "welford1962", "chan1979"})
        EXPECT_TRUE(has(all, k)) << k;
}

TEST(Cite, EveryReferenceHasPlainTextAndBalancedBibtex) {
    engine::SceneParams p;
    p.integrator.scheme = engine::Scheme::gear4;
    p.material.normal_law = engine::NormalLaw::hertz;
    p.fields.enabled = true;
    engine::SceneParams v;
    CiteUse use = cite_use({p, v});
    use.code_version = "0.4.0+abc1234";
    const auto keys = cited_keys(use);
    std::ostringstream text, bib;
    write_citations(text, use, true, false);
    write_citations(bib, use, false, true);
    const std::string t = text.str(), b = bib.str();
    for (const auto& k : keys) {
        EXPECT_NE(t.find("[" + k + "] "), std::string::npos) << k;
        EXPECT_NE(b.find("{" + k + ",\n"), std::string::npos) << k;
    }
    EXPECT_EQ(static_cast<std::size_t>(std::count(b.begin(), b.end(), '@')), keys.size());
    EXPECT_EQ(std::count(b.begin(), b.end(), '{'), std::count(b.begin(), b.end(), '}'));
    // plain text has no BibTeX markup; the code version is named
    EXPECT_EQ(t.find_first_of("{}\\"), std::string::npos) << t;
    EXPECT_NE(t.find("Garcimart\xC3\xADn"), std::string::npos);
    EXPECT_NE(t.find("version 0.4.0+abc1234"), std::string::npos);
    EXPECT_NE(b.find("version 0.4.0+abc1234"), std::string::npos);
    EXPECT_NE(t.find("doi:10.1063/1.3669495"), std::string::npos);
}

}  // namespace
}  // namespace hopper::cli
