// SPDX-License-Identifier: AGPL-3.0-or-later
// A small JSON reader for the render metadata (docs/metadata.md): enough JSON for any file,
// with errors that give the line and column.

#ifndef PLENOPTIC_TOOLS_JSON_H
#define PLENOPTIC_TOOLS_JSON_H

#include <string>
#include <utility>
#include <vector>

namespace plenoptic {
namespace json {

enum class Type { Null, Bool, Number, String, Array, Object };

struct Value {
    Type type = Type::Null;
    bool boolean = false;
    double number = 0;
    bool integral = false;  // the number was written without fraction or exponent
    std::string string;
    std::vector<Value> items;                            // Array
    std::vector<std::pair<std::string, Value>> members;  // Object, in file order

    // The member named `key` of an object, or nullptr (also when this is not an object).
    const Value* member(const std::string& key) const;
};

// "null", "a number", "an array", ... for messages.
const char* type_name(Type type);

// Parses a whole JSON text. On failure returns false and sets `error` to
// "line L, column C: what was wrong".
bool parse(const std::string& text, Value* out, std::string* error);

} // namespace json
} // namespace plenoptic

#endif
