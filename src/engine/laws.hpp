#pragma once
// The registry of contact laws (issue 28; docs/model.md, "Contact forces"), private to the
// engine: the one list that the kernels (kernel.cpp) and every build of the force pass
// (force_batch_impl.hpp: the reference and each instruction set's batched pass) instantiate. Adding
// a law is a value type with evaluate() (contact.hpp has the three of today and their contract) and
// one entry in `Laws`; nothing else lists laws. A scene's law is chosen once, by System (law_for,
// system.cpp), as its index in this list.

#include <array>
#include <cstddef>
#include <type_traits>

#include "hopper/engine/contact.hpp"

namespace hopper::engine::detail {

template <class... L>
struct LawList {
    static constexpr std::size_t size = sizeof...(L);
};

// The registry. The order is the law's id (law_id<Law>); it is not stored anywhere.
using Laws = LawList<FrictionlessLaw, ViscousFrictionLaw, SpringFrictionLaw, HertzSpringLaw,
                     WithRolling<SpringFrictionLaw>, WithRolling<HertzSpringLaw>>;
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

}  // namespace hopper::engine::detail
