// The plant text parser: transfer functions typed the way the report writes them.
#pragma once

#include "linsys/tf.hpp"

#include <cstddef>
#include <optional>
#include <string>
#include <string_view>

namespace mcg::linsys {

/// A parsed expression. `domain` is empty for a constant (no s or z in the text).
struct ParsedTf {
  Tf tf;
  std::optional<Domain> domain;
};

/// The longest expression parse_tf() reads, in characters: a plant of the rig takes under 100; a
/// `[plant] tf` of an INI has no other bound.
inline constexpr std::size_t k_max_tf_chars = 65536;
/// The deepest nesting of '(' (and exp's parentheses) parse_tf() reads.
inline constexpr int k_max_tf_depth = 200;

/// Parses an expression in s or in z:
///   expr   := term (('+'|'-') term)*
///   term   := factor (('*'|'/') factor)*
///   factor := ('+'|'-') factor | power
///   power  := atom ('^' ['+'|'-'] integer)?
///   atom   := number | 's' | 'z' | '(' expr ')' | 'exp' '(' expr ')'
/// e.g. "16.557/((s/65+1)*(s/950+1))", "4658*(s/500+1)/s", "0.5*exp(-0.002*s)/(s+1)",
/// "(11.645*z - 6.987)/(z - 1)", "z^-1". exp() takes a polynomial of degree <= 1 in s:
/// exp(c − τ·s) = e^c·e^(−τs), a delay τ >= 0. Terms of a sum must carry the same delay.
/// An exponent is at most 64; every intermediate numerator and denominator stays within
/// k_max_degree and finite ("degree 4096 above the limit of 256 at character N", "number out of
/// range at character N", "exponent too large (at most 64) at character N"). The text is at most
/// k_max_tf_chars long and nests at most k_max_tf_depth parentheses; a chain of signs (`--s`)
/// costs no recursion, so no input exhausts the stack.
/// Errors are mcg::Error "<where>: <what> at character N" (N counts from 1), e.g.
/// "--plant: unbalanced '(' at character 12", "--plant: s and z mixed at character 9".
ParsedTf parse_tf(std::string_view text, const std::string& where);

}  // namespace mcg::linsys
