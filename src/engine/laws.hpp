#pragma once
// The registry of contact laws (issues 28, 42; docs/model.md, "Contact forces"), private to the
// engine: the one list that the kernels (kernel.cpp) and every build of the force pass
// (force_batch_impl.hpp: the reference and each instruction set's batched pass) instantiate.
// Adding a law is a value type with evaluate() and its `normal` and `tangential` parts
// (contact.hpp has the contract; law_hertz_viscous.hpp is a law in a file of its own) and one
// entry in `Laws`; nothing else lists laws. A scene's law is chosen once, by System, as the
// registered law with the scene's normal and tangential parts (law_for below).

#include <array>
#include <cstddef>
#include <type_traits>

#include "hopper/engine/contact.hpp"
#include "hopper/engine/law_hertz_viscous.hpp"

namespace hopper::engine::detail {

template <class... L>
struct LawList {
    static constexpr std::size_t size = sizeof...(L);
};

// The registry. The order is the law's id (law_id<Law>); it is not stored anywhere.
using Laws = LawList<FrictionlessLaw, ViscousFrictionLaw, SpringFrictionLaw, HertzSpringLaw,
                     WithRolling<SpringFrictionLaw>, WithRolling<HertzSpringLaw>, HertzViscousLaw,
                     WithRollingSpring<SpringFrictionLaw>>;
inline constexpr std::size_t law_count = Laws::size;

namespace laws_impl {
template <class Law, class... L>
constexpr std::size_t index_in(LawList<L...>) {
    std::size_t i = 0, found = sizeof...(L);
    ((std::is_same_v<Law, L> ? (found = i) : 0, ++i), ...);
    return found;
}
}  // namespace laws_impl

// The id of a registered law (a compile error for a type that is not in the list).
template <class Law>
inline constexpr int law_id = [] {
    constexpr std::size_t i = laws_impl::index_in<Law>(Laws{});
    static_assert(i < law_count, "the contact law is not in the registry (laws.hpp)");
    return int(i);
}();

// { make.template operator()<L>() for every law L of the registry }, in its order: the tables of
// function pointers each force path builds from the list.
template <class Make, class... L>
constexpr auto for_each_law(LawList<L...>, Make make) {
    return std::array{make.template operator()<L>()...};
}
template <class Make>
constexpr auto for_each_law(Make make) {
    return for_each_law(Laws{}, make);
}

// What System needs of a law it did not instantiate: its parts and whether it keeps springs.
struct LawTraits {
    NormalLaw normal;
    TangentialLaw tangential;
    bool rolling;
    bool rolling_spring;  // the rolling resistance is a spring: a third history column
    bool has_history;
};
inline constexpr auto law_traits = for_each_law([]<class L>() {
    return LawTraits{L::normal, L::tangential, law_resists_rolling<L>, law_has_rolling_spring<L>,
                     L::has_history};
});

// The id of the registered law with these parts, or -1 when none has them.
constexpr int law_for(NormalLaw normal, TangentialLaw tangential, bool rolling,
                      bool rolling_spring = false) {
    for (std::size_t i = 0; i < law_count; ++i)
        if (law_traits[i].normal == normal && law_traits[i].tangential == tangential &&
            law_traits[i].rolling == rolling && law_traits[i].rolling_spring == rolling_spring)
            return int(i);
    return -1;
}

}  // namespace hopper::engine::detail
