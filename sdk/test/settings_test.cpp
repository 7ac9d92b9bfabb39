// beslam::sdk::Settings: one declaration gives the schema and the typed reader; a value that does not fit
// the declaration (unknown key, wrong type, out of range, not a choice, wrong list length, missing) is a
// ConfigError naming the setting.
#include "beslam/sdk/settings.hpp"

#include <gtest/gtest.h>

#include <array>
#include <string>
#include <vector>

namespace beslam::sdk {
namespace {

enum class Mode { fast, exact };
struct Inner {
  double low = 0;
};
struct Options {
  bool flag = false;
  int count = 0;
  uint64_t seed = 0;
  double gate = 0;
  float weight = 0;
  std::string name, file;
  std::vector<double> list;
  std::array<double, 3> size{};
  Mode mode = Mode::fast;
  Inner inner;
  int untouched = 17;  // no setting: read() leaves it
};

const Settings<Options> kSettings{
    setting(&Options::flag, "flag", "true", "a switch"),
    setting(&Options::count, "count", "3", 1, 10, "a count"),
    setting(&Options::seed, "seed", "42", 0, 2147483647.0, "a seed"),
    setting(&Options::gate, "gate", "2.0", 0.01, 100, "a distance"),
    setting(&Options::weight, "weight", "0.5", 1, 0, "unbounded"),
    setting(&Options::name, "name", "a", "a|bb|c", "one of three"),
    path(&Options::file, "file", "\"\"", "a file"),
    setting(&Options::list, "list", "[1, 2]", -5, 5, "numbers"),
    setting(&Options::size, "size", "[3.9, 1.6, 1.5]", 0.1, 20, "three numbers"),
    choice(&Options::mode, "mode", "exact", {{"fast", Mode::fast}, {"exact", Mode::exact}}, "solver"),
    nested(&Options::inner, setting(&Inner::low, "low", "30", 0, 1000, "inner member")),
};

beslam_config_value number(const char* key, int32_t type, double v) { return {key, type, 0, v, nullptr, nullptr, 0}; }
beslam_config_value text(const char* key, int32_t type, const char* t) { return {key, type, 0, 0, t, nullptr, 0}; }

struct Values {
  std::vector<double> list = {1.5, -2}, size = {4, 1.7, 1.4};
  std::vector<beslam_config_value> v = {number("flag", BESLAM_CONFIG_BOOL, 0),
                                        number("count", BESLAM_CONFIG_INT, 7),
                                        number("seed", BESLAM_CONFIG_INT, 1234567),
                                        number("gate", BESLAM_CONFIG_DOUBLE, 0.25),
                                        number("weight", BESLAM_CONFIG_DOUBLE, -3),
                                        text("name", BESLAM_CONFIG_STRING, "bb"),
                                        text("file", BESLAM_CONFIG_PATH, "/x/y"),
                                        {"list", BESLAM_CONFIG_DOUBLE_LIST, 0, 0, nullptr, list.data(), 2},
                                        {"size", BESLAM_CONFIG_DOUBLE_LIST, 0, 0, nullptr, size.data(), 3},
                                        text("mode", BESLAM_CONFIG_STRING, "fast"),
                                        number("low", BESLAM_CONFIG_DOUBLE, 45)};
  beslam_config_value& operator[](const std::string& key) {
    for (auto& x : v)
      if (key == x.key) return x;
    throw std::out_of_range(key);
  }
  Config config() const { return Config(v.data(), static_cast<uint32_t>(v.size())); }
};

std::string errorOf(const Values& values) {
  try {
    kSettings.read(values.config());
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "";
}

TEST(Settings, TheDeclarationIsTheSchema) {
  ASSERT_EQ(kSettings.size(), 11u);
  const beslam_config_field* f = kSettings.fields();
  EXPECT_STREQ(f[0].key, "flag");
  EXPECT_EQ(f[0].type, BESLAM_CONFIG_BOOL);
  EXPECT_EQ(f[1].type, BESLAM_CONFIG_INT);
  EXPECT_EQ(f[2].type, BESLAM_CONFIG_INT);  // uint64_t is an integer setting
  EXPECT_EQ(f[3].type, BESLAM_CONFIG_DOUBLE);
  EXPECT_STREQ(f[3].default_value, "2.0");  // the default text as declared, for `beslam plugins`
  EXPECT_EQ(f[3].min_value, 0.01);
  EXPECT_EQ(f[3].max_value, 100);
  EXPECT_EQ(f[4].type, BESLAM_CONFIG_DOUBLE);  // float too
  EXPECT_STREQ(f[5].choices, "a|bb|c");
  EXPECT_EQ(f[6].type, BESLAM_CONFIG_PATH);
  EXPECT_EQ(f[7].type, BESLAM_CONFIG_DOUBLE_LIST);
  EXPECT_EQ(f[8].type, BESLAM_CONFIG_DOUBLE_LIST);
  EXPECT_EQ(f[9].type, BESLAM_CONFIG_STRING);
  EXPECT_STREQ(f[9].choices, "fast|exact");  // from the names given to choice()
  EXPECT_STREQ(f[9].default_value, "exact");
  EXPECT_STREQ(f[10].key, "low");
  EXPECT_STREQ(f[10].doc, "inner member");
  for (uint32_t i = 0; i < kSettings.size(); ++i) EXPECT_EQ(f[i].required, 0) << f[i].key;
}

TEST(Settings, ReadsEveryValueTyped) {
  const Values values;
  Options o;
  kSettings.read(values.config(), o);
  EXPECT_FALSE(o.flag);
  EXPECT_EQ(o.count, 7);
  EXPECT_EQ(o.seed, 1234567u);
  EXPECT_EQ(o.gate, 0.25);
  EXPECT_EQ(o.weight, -3.0f);
  EXPECT_EQ(o.name, "bb");
  EXPECT_EQ(o.file, "/x/y");
  EXPECT_EQ(o.list, (std::vector<double>{1.5, -2}));
  EXPECT_EQ(o.size, (std::array<double, 3>{4, 1.7, 1.4}));
  EXPECT_EQ(o.mode, Mode::fast);
  EXPECT_EQ(o.inner.low, 45);
  EXPECT_EQ(o.untouched, 17);
}

TEST(Settings, AValueThatDoesNotFitIsAnErrorNamingTheSetting) {
  {
    Values v;
    v.v.push_back(number("gates", BESLAM_CONFIG_DOUBLE, 1));
    EXPECT_EQ(errorOf(v),
              "unknown setting 'gates' (known: flag, count, seed, gate, weight, name, file, list, size, mode, low)");
  }
  {
    Values v;
    v["count"].type = BESLAM_CONFIG_DOUBLE;
    EXPECT_EQ(errorOf(v), "setting 'count': expected an integer, got a number");
  }
  {
    Values v;
    v["count"].number = 11;
    EXPECT_EQ(errorOf(v), "setting 'count': value 11.000000 is out of range [1.000000, 10.000000]");
  }
  {
    Values v;
    v["gate"].number = 0.001;
    EXPECT_EQ(errorOf(v), "setting 'gate': value 0.001000 is out of range [0.010000, 100.000000]");
  }
  {
    Values v;
    v["weight"].number = 1e300;  // min > max: unbounded
    EXPECT_EQ(errorOf(v), "");
  }
  {
    Values v;
    v["name"].text = "b";
    EXPECT_EQ(errorOf(v), "setting 'name': 'b' is not one of a|bb|c");
  }
  {
    Values v;
    v["mode"].text = "slow";
    EXPECT_EQ(errorOf(v), "setting 'mode': 'slow' is not one of fast|exact");
  }
  {
    Values v;
    v.list[1] = 6;
    EXPECT_EQ(errorOf(v), "setting 'list': element 2 (6.000000) is out of range [-5.000000, 5.000000]");
  }
  {
    Values v;
    v["size"].list_size = 2;
    EXPECT_EQ(errorOf(v), "setting 'size': expected 3 numbers, got 2");
  }
  {
    Values v;
    v.v.erase(v.v.begin() + 3);  // gate
    EXPECT_EQ(errorOf(v), "setting 'gate' is missing");
  }
  {
    Values v;
    v["flag"].type = BESLAM_CONFIG_STRING;
    EXPECT_EQ(errorOf(v), "setting 'flag': expected a boolean, got a string");
  }
}

TEST(Settings, IntegerListsAndParsedStringsCheckTheirValues) {
  struct Ids {
    std::vector<int> ids;
    std::vector<int> parsedIds;
  };
  auto parse = [](const std::string& text) {
    if (text != "one" && text != "two") throw std::invalid_argument("unknown name '" + text + "'");
    return std::vector<int>{text == "one" ? 1 : 2};
  };
  const Settings<Ids> settings{setting(&Ids::ids, "ids", "[2]", 0, 100, "class ids"),
                               parsed(&Ids::parsedIds, "name", "one", nullptr, "a name", parse)};
  EXPECT_EQ(settings.fields()[0].type, BESLAM_CONFIG_DOUBLE_LIST);
  EXPECT_EQ(settings.fields()[1].type, BESLAM_CONFIG_STRING);
  std::vector<double> list = {1, 3};
  std::vector<beslam_config_value> v = {{"ids", BESLAM_CONFIG_DOUBLE_LIST, 0, 0, nullptr, list.data(), 2},
                                        text("name", BESLAM_CONFIG_STRING, "two")};
  const Config config(v.data(), 2);
  const Ids ids = settings.read(config);
  EXPECT_EQ(ids.ids, (std::vector<int>{1, 3}));
  EXPECT_EQ(ids.parsedIds, (std::vector<int>{2}));
  list[1] = 2.5;
  EXPECT_THROW(
      try { settings.read(config); } catch (const ConfigError& e) {
        EXPECT_STREQ(e.what(), "setting 'ids': element 2 (2.500000) is not a whole number");
        throw;
      },
      ConfigError);
  list[1] = 3;
  v[1].text = "three";
  EXPECT_THROW(
      try { settings.read(config); } catch (const ConfigError& e) {
        EXPECT_STREQ(e.what(), "name: unknown name 'three'");
        throw;
      },
      ConfigError);
}

TEST(Settings, ARequiredSettingHasNoDefault) {
  struct Required {
    std::string model;
  };
  const Settings<Required> settings{path(&Required::model, "model", nullptr, "model file (required)")};
  EXPECT_EQ(settings.fields()[0].required, 1);
  EXPECT_EQ(settings.fields()[0].default_value, nullptr);
}

}  // namespace
}  // namespace beslam::sdk
