// LawRegistry: the control laws a teleoperation task can run, by name, with their settings.
#pragma once

#include <functional>
#include <map>
#include <memory>
#include <string>
#include <string_view>
#include <tuple>
#include <type_traits>
#include <utility>
#include <vector>

#include "saw/deploy/params.hpp"
#include "saw/deploy/registry.hpp"
#include "saw/description.hpp"
#include "saw/provided_interface.hpp"
#include "saw/state_table.hpp"
#include "saw/teleop/law.hpp"
#include "saw/teleop/law_setting.hpp"

namespace saw::teleop {

// A law behind one virtual call per operation: what the task holds (built outside the RT path).
class LawModel {
 public:
  virtual ~LawModel() = default;
  virtual std::string_view name() const noexcept = 0;
  virtual void reset(const LawInputs& in) noexcept = 0;
  virtual void hold(const LawInputs& in) noexcept = 0;
  virtual LawCommand step(const LawInputs& in) noexcept = 0;
  virtual std::uint64_t refusals() const noexcept = 0;
  virtual int last_refusal() const noexcept = 0;
  // The law sets LawCommand::slave_goal: a slave that follows a pose can be driven by it.
  virtual bool gives_slave_goal() const noexcept = 0;
  virtual bool gives_no_force() const noexcept = 0;
  // Setup: where its number setting `name` lives (read it for the value as it is now; the law's
  // settings are its members, they do not move), and its unit; nullptr: no such setting.
  virtual const double* setting_address(std::string_view name, std::string_view& unit) const noexcept = 0;
  // Setup: one slot per declared input (law_input.hpp), in declaration order, for the task to
  // require on the named side and read every cycle.
  virtual std::vector<std::unique_ptr<detail::InputSlot>> make_inputs() const = 0;
  // Setup: one slot per declared output (law_output.hpp), in declaration order.
  virtual std::vector<std::unique_ptr<detail::OutputSlot>> make_outputs() const = 0;
  // Setup: each declared setting as a latched state column and read command `name`, and (when
  // it is a command) `set_<name>`, bounded; a refused value counts in `rejected`. Each declared
  // read-out as a state column and read command.
  virtual void provide_settings(ProvidedInterface& p, StateTable& table, std::uint64_t& rejected) = 0;
  // Its declared settings (name, unit, bounds, numbers, whether set_<name> exists) into `d`, in
  // declaration order; those beyond ComponentDescription::max_settings are left out.
  virtual void describe(ComponentDescription& d) const noexcept = 0;
};

namespace detail {

template <class L>
class LawHolder final : public LawModel {
 public:
  LawHolder(const typename L::Settings& s, const LawContext& ctx) : law_(s, ctx) {}
  std::string_view name() const noexcept override { return L::name; }
  void reset(const LawInputs& in) noexcept override { law_.reset(in); }
  void hold(const LawInputs& in) noexcept override {
    if constexpr (requires { law_.hold(in); })
      law_.hold(in);
    else
      law_.reset(in);
  }
  LawCommand step(const LawInputs& in) noexcept override { return law_.step(in); }
  std::uint64_t refusals() const noexcept override {
    if constexpr (requires { law_.refusals(); })
      return law_.refusals();
    else
      return 0;
  }
  int last_refusal() const noexcept override {
    if constexpr (requires { law_.last_refusal(); })
      return law_.last_refusal();
    else
      return 0;
  }
  bool gives_slave_goal() const noexcept override {
    if constexpr (requires { L::gives_slave_goal; })
      return L::gives_slave_goal;
    else
      return false;
  }
  bool gives_no_force() const noexcept override {
    if constexpr (requires { L::gives_no_force; })
      return L::gives_no_force;
    else
      return false;
  }
  const double* setting_address(std::string_view name, std::string_view& unit) const noexcept override {
    const double* found = nullptr;
    // settings() is the law's read-back (and set_<name>'s target): reading it changes nothing.
    const typename L::Settings& s = const_cast<L&>(law_).settings();
    std::apply(
        [&](const auto&... d) {
          const auto one = [&](const auto& setting) {
            if constexpr (std::is_same_v<typename std::decay_t<decltype(setting)>::Value, double>) {
              if (found == nullptr && setting.name == name) {
                found = &(s.*setting.member);
                unit = setting.unit;
              }
            }
          };
          (void)one;  // a law without settings
          (one(d), ...);
        },
        L::declared_settings);
    return found;
  }
  std::vector<std::unique_ptr<detail::InputSlot>> make_inputs() const override {
    std::vector<std::unique_ptr<detail::InputSlot>> slots;
    if constexpr (requires { L::declared_inputs; })
      std::apply([&](const auto&... in) { (slots.push_back(make_slot(in)), ...); }, L::declared_inputs);
    return slots;
  }
  std::vector<std::unique_ptr<detail::OutputSlot>> make_outputs() const override {
    std::vector<std::unique_ptr<detail::OutputSlot>> slots;
    if constexpr (requires { L::declared_outputs; })
      std::apply([&](const auto&... out) { (slots.push_back(make_slot(out)), ...); }, L::declared_outputs);
    return slots;
  }
  void provide_settings(ProvidedInterface& p, StateTable& table, std::uint64_t& rejected) override {
    std::apply([&](const auto&... s) { (provide(p, table, rejected, s), ...); }, L::declared_settings);
    if constexpr (requires { L::declared_readouts; })
      std::apply(
          [&](const auto&... r) {
            (p.add_command_read(std::string(r.name),
                                table.add_column(std::string(r.name), &(law_.*r.member))),
             ...);
          },
          L::declared_readouts);
  }
  void describe(ComponentDescription& d) const noexcept override {
    d.setting_count = 0;
    std::apply([&](const auto&... s) { (describe(d, s), ...); }, L::declared_settings);
  }
  L& law() noexcept { return law_; }

 private:
  template <class T>
  static std::unique_ptr<InputSlot> make_slot(const Input<T>& in) {
    return std::make_unique<TypedInputSlot<T>>(in);
  }
  template <class T>
  static std::unique_ptr<OutputSlot> make_slot(const Output<T>& out) {
    return std::make_unique<TypedOutputSlot<T>>(out);
  }
  template <class T>
  static void describe(ComponentDescription& d, const Setting<typename L::Settings, T>& s) noexcept {
    if (d.setting_count >= ComponentDescription::max_settings) return;
    DeclaredSetting& out = d.settings[d.setting_count++];
    ComponentDescription::set(out.name, s.name);
    ComponentDescription::set(out.unit, s.unit);
    out.min = s.min;
    out.max = s.max;
    if constexpr (requires { SettingCodec<T>::count; }) out.count = SettingCodec<T>::count;
    out.command = s.command;
  }
  template <class T>
  void provide(ProvidedInterface& p, StateTable& table, std::uint64_t& rejected,
               const Setting<typename L::Settings, T>& s) {
    const std::string name(s.name);
    // The column reads the value in force every cycle: what was set is what is shown.
    p.add_command_read(name, table.add_column(name, &(law_.settings().*s.member)));
    if (!s.command) return;
    p.add_command_write<T>("set_" + name, [this, &rejected, s](const T& v) {
      if (!SettingCodec<T>::within(v, s.min, s.max) || (s.valid != nullptr && !s.valid(v)))
        return void(++rejected);
      const typename L::Settings before = law_.settings();
      law_.settings().*s.member = v;
      if constexpr (requires { law_.on_set(s.name, before); }) law_.on_set(s.name, before);
    });
    // Declared: the bridge and the gateway refuse the same values before they get here.
    if constexpr (SettingCodec<T>::declares_limits)
      if (std::isfinite(s.min) && std::isfinite(s.max)) p.limit("set_" + name, s.min, s.max);
  }
  L law_;
};

// Reads one declared setting from the deployment into `out`.
template <class S, class T>
void parse_setting(const deploy::Params& p, const Setting<S, T>& s, S& out) {
  const std::string key(s.name);
  out.*s.member = SettingCodec<T>::parse(p, key, s.min, s.max, out.*s.member);
  if (s.valid != nullptr && !s.valid(out.*s.member)) p.fail_at(key, std::string(s.invalid_why));
}

}  // namespace detail

// A law chosen, with its settings, not built yet: copyable (a deployment keeps it).
struct LawSpec {
  std::string name;
  std::function<std::unique_ptr<LawModel>(const LawContext&)> make;
};

template <Law L>
LawSpec law_spec(const typename L::Settings& settings = {}) {
  return {std::string(L::name), [settings](const LawContext& ctx) -> std::unique_ptr<LawModel> {
            return std::make_unique<detail::LawHolder<L>>(settings, ctx);
          }};
}

// One row of a law's settings table (docs/teleop-laws.md).
struct SettingRow {
  std::string name, shape, unit, bounds, fallback, command, help;
};

// The laws a deployment may name in `law:`. Each registers with one line, add<L>().
class LawRegistry {
 public:
  struct Entry {
    std::string description;
    // Reads the law's settings from the component's `params:` (file:line:key errors).
    std::function<LawSpec(const deploy::Params&)> parse;
    std::vector<SettingRow> rows;
    std::vector<SettingRow> readouts;  // name, unit, help
    const void* identity = nullptr;    // the law's type (a plug-in loaded again registers it again)
  };

  // Throws std::invalid_argument for a name taken by another law, or a setting named like one
  // of the task's own keys (`reserved`). The same law again is no change.
  template <Law L>
  void add() {
    static_assert(std::tuple_size_v<std::remove_cvref_t<decltype(L::declared_settings)>> <=
                      ComponentDescription::max_settings,
                  "a law declares at most ComponentDescription::max_settings settings: its description "
                  "(and a GUI's panel made from it) carries no more");
    Entry e;
    e.identity = &L::name;
    e.description = std::string(L::description);
    e.parse = [](const deploy::Params& p) {
      typename L::Settings s{};
      std::apply([&](const auto&... d) { (detail::parse_setting(p, d, s), ...); }, L::declared_settings);
      return law_spec<L>(s);
    };
    const typename L::Settings defaults{};
    std::apply([&](const auto&... d) { (e.rows.push_back(row(d, defaults)), ...); }, L::declared_settings);
    if constexpr (requires { L::declared_readouts; })
      std::apply(
          [&](const auto&... r) {
            (e.readouts.push_back(
                 {std::string(r.name), "", std::string(r.unit), "", "", "", std::string(r.help)}),
             ...);
          },
          L::declared_readouts);
    add_entry(std::string(L::name), std::move(e));
  }

  const Entry* find(const std::string& name) const;
  const std::map<std::string, Entry>& laws() const noexcept { return laws_; }
  std::string names() const;  // "a, b": for error messages
  // The settings of every law as markdown tables (docs/teleop-laws.md's generated part).
  std::string markdown() const;

  // The task's own parameters: a law's setting may not take these names.
  static const std::vector<std::string>& reserved();

 private:
  template <class S, class T>
  static SettingRow row(const Setting<S, T>& s, const S& defaults) {
    std::string bounds;
    if (std::isfinite(s.min) || std::isfinite(s.max))
      bounds = "[" + setting_number(s.min) + ", " + setting_number(s.max) + "]";
    else
      bounds = "finite";
    if constexpr (std::is_same_v<T, bool>) bounds = "";
    return {std::string(s.name),
            std::string(SettingCodec<T>::shape),
            std::string(s.unit),
            bounds,
            SettingCodec<T>::text(defaults.*s.member),
            s.command ? "set_" + std::string(s.name) : "",
            std::string(s.help)};
  }
  void add_entry(std::string name, Entry e);
  std::map<std::string, Entry> laws_;
};

// The laws of a component registry: the built-in ones (teleop's register_components adds them,
// laws.cpp), and those a plug-in adds from its registration function, given the same registry:
//   void register_law(saw::deploy::ComponentRegistry& r) { saw::teleop::laws(r).add<MyLaw>(); }
LawRegistry& laws(deploy::ComponentRegistry& registry);
// The built-in laws alone (the docs' tables, tests).
void add_builtin_laws(LawRegistry& registry);

}  // namespace saw::teleop
