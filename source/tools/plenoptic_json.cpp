// SPDX-License-Identifier: AGPL-3.0-or-later
// Recursive-descent JSON reader (RFC 8259), strict: no comments, no trailing commas.

#include "plenoptic_json.h"

#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>

namespace plenoptic {
namespace json {

namespace {

// Nesting deeper than this is refused rather than risking the stack.
const int kMaxDepth = 200;

class Parser {
public:
    explicit Parser(const std::string& text) : text_(text) {}

    bool parse_document(Value* out, std::string* error)
    {
        skip_space();
        bool ok = parse_value(out, 0);
        if (ok) {
            skip_space();
            if (pos_ != text_.size())
                ok = fail("unexpected text after the JSON value");
        }
        if (!ok)
            *error = where() + ": " + message_;
        return ok;
    }

private:
    bool fail(const std::string& message)
    {
        if (message_.empty())
            message_ = message;
        return false;
    }

    std::string where() const
    {
        size_t line = 1, column = 1;
        for (size_t i = 0; i < pos_ && i < text_.size(); ++i) {
            if (text_[i] == '\n') {
                ++line;
                column = 1;
            } else {
                ++column;
            }
        }
        return "line " + std::to_string(line) + ", column " + std::to_string(column);
    }

    void skip_space()
    {
        while (pos_ < text_.size() &&
               (text_[pos_] == ' ' || text_[pos_] == '\t' || text_[pos_] == '\n' || text_[pos_] == '\r'))
            ++pos_;
    }

    // 'c' for printable ASCII, else its byte value (never raw bytes in a message).
    static std::string quote_char(char c)
    {
        const unsigned char u = static_cast<unsigned char>(c);
        if (u >= 0x20 && u < 0x7f)
            return std::string("'") + c + "'";
        char buffer[16];
        std::snprintf(buffer, sizeof buffer, "byte 0x%02x", u);
        return buffer;
    }

    bool literal(const char* word)
    {
        const size_t n = std::strlen(word);
        if (text_.compare(pos_, n, word) != 0)
            return fail("expected a JSON value");
        pos_ += n;
        return true;
    }

    bool parse_value(Value* out, int depth)
    {
        if (depth > kMaxDepth)
            return fail("nesting too deep");
        if (pos_ >= text_.size())
            return fail("unexpected end of file");
        const char c = text_[pos_];
        if (c == '{')
            return parse_object(out, depth);
        if (c == '[')
            return parse_array(out, depth);
        if (c == '"') {
            out->type = Type::String;
            return parse_string(&out->string);
        }
        if (c == 't') {
            out->type = Type::Bool;
            out->boolean = true;
            return literal("true");
        }
        if (c == 'f') {
            out->type = Type::Bool;
            out->boolean = false;
            return literal("false");
        }
        if (c == 'n') {
            out->type = Type::Null;
            return literal("null");
        }
        if (c == '-' || (c >= '0' && c <= '9'))
            return parse_number(out);
        return fail("unexpected character " + quote_char(c));
    }

    bool parse_object(Value* out, int depth)
    {
        out->type = Type::Object;
        ++pos_;  // {
        skip_space();
        if (pos_ < text_.size() && text_[pos_] == '}') {
            ++pos_;
            return true;
        }
        for (;;) {
            skip_space();
            if (pos_ >= text_.size() || text_[pos_] != '"')
                return fail("expected a member name in double quotes");
            std::string key;
            if (!parse_string(&key))
                return false;
            skip_space();
            if (pos_ >= text_.size() || text_[pos_] != ':')
                return fail("expected ':' after member name \"" + key + "\"");
            ++pos_;
            skip_space();
            out->members.push_back(std::make_pair(key, Value()));
            if (!parse_value(&out->members.back().second, depth + 1))
                return false;
            skip_space();
            if (pos_ < text_.size() && text_[pos_] == ',') {
                ++pos_;
                continue;
            }
            if (pos_ < text_.size() && text_[pos_] == '}') {
                ++pos_;
                return true;
            }
            return fail("expected ',' or '}' in an object");
        }
    }

    bool parse_array(Value* out, int depth)
    {
        out->type = Type::Array;
        ++pos_;  // [
        skip_space();
        if (pos_ < text_.size() && text_[pos_] == ']') {
            ++pos_;
            return true;
        }
        for (;;) {
            skip_space();
            out->items.push_back(Value());
            if (!parse_value(&out->items.back(), depth + 1))
                return false;
            skip_space();
            if (pos_ < text_.size() && text_[pos_] == ',') {
                ++pos_;
                continue;
            }
            if (pos_ < text_.size() && text_[pos_] == ']') {
                ++pos_;
                return true;
            }
            return fail("expected ',' or ']' in an array");
        }
    }

    static void append_utf8(unsigned code, std::string* out)
    {
        if (code < 0x80) {
            *out += char(code);
        } else if (code < 0x800) {
            *out += char(0xC0 | (code >> 6));
            *out += char(0x80 | (code & 0x3F));
        } else if (code < 0x10000) {
            *out += char(0xE0 | (code >> 12));
            *out += char(0x80 | ((code >> 6) & 0x3F));
            *out += char(0x80 | (code & 0x3F));
        } else {
            *out += char(0xF0 | (code >> 18));
            *out += char(0x80 | ((code >> 12) & 0x3F));
            *out += char(0x80 | ((code >> 6) & 0x3F));
            *out += char(0x80 | (code & 0x3F));
        }
    }

    bool hex4(unsigned* code)
    {
        if (pos_ + 4 > text_.size())
            return fail("truncated \\u escape");
        unsigned v = 0;
        for (int i = 0; i < 4; ++i) {
            const char h = text_[pos_++];
            v <<= 4;
            if (h >= '0' && h <= '9')
                v |= unsigned(h - '0');
            else if (h >= 'a' && h <= 'f')
                v |= unsigned(h - 'a' + 10);
            else if (h >= 'A' && h <= 'F')
                v |= unsigned(h - 'A' + 10);
            else
                return fail("bad hex digit in a \\u escape");
        }
        *code = v;
        return true;
    }

    bool parse_string(std::string* out)
    {
        ++pos_;  // opening quote
        for (;;) {
            if (pos_ >= text_.size())
                return fail("unterminated string");
            const unsigned char c = static_cast<unsigned char>(text_[pos_++]);
            if (c == '"')
                return true;
            if (c < 0x20)
                return fail("control character inside a string");
            if (c != '\\') {
                *out += char(c);
                continue;
            }
            if (pos_ >= text_.size())
                return fail("unterminated string");
            const char e = text_[pos_++];
            switch (e) {
            case '"': *out += '"'; break;
            case '\\': *out += '\\'; break;
            case '/': *out += '/'; break;
            case 'b': *out += '\b'; break;
            case 'f': *out += '\f'; break;
            case 'n': *out += '\n'; break;
            case 'r': *out += '\r'; break;
            case 't': *out += '\t'; break;
            case 'u': {
                unsigned code;
                if (!hex4(&code))
                    return false;
                if (code >= 0xD800 && code < 0xDC00 && text_.compare(pos_, 2, "\\u") == 0) {
                    pos_ += 2;
                    unsigned low;
                    if (!hex4(&low))
                        return false;
                    if (low >= 0xDC00 && low < 0xE000)
                        code = 0x10000 + ((code - 0xD800) << 10) + (low - 0xDC00);
                }
                append_utf8(code, out);
                break;
            }
            default: return fail("unknown escape after a backslash: " + quote_char(e));
            }
        }
    }

    bool parse_number(Value* out)
    {
        const size_t start = pos_;
        bool integral = true;
        if (text_[pos_] == '-')
            ++pos_;
        if (pos_ >= text_.size() || !(text_[pos_] >= '0' && text_[pos_] <= '9'))
            return fail("malformed number");
        if (text_[pos_] == '0')
            ++pos_;
        else
            while (pos_ < text_.size() && text_[pos_] >= '0' && text_[pos_] <= '9')
                ++pos_;
        if (pos_ < text_.size() && text_[pos_] == '.') {
            integral = false;
            ++pos_;
            if (pos_ >= text_.size() || !(text_[pos_] >= '0' && text_[pos_] <= '9'))
                return fail("malformed number: no digit after '.'");
            while (pos_ < text_.size() && text_[pos_] >= '0' && text_[pos_] <= '9')
                ++pos_;
        }
        if (pos_ < text_.size() && (text_[pos_] == 'e' || text_[pos_] == 'E')) {
            integral = false;
            ++pos_;
            if (pos_ < text_.size() && (text_[pos_] == '+' || text_[pos_] == '-'))
                ++pos_;
            if (pos_ >= text_.size() || !(text_[pos_] >= '0' && text_[pos_] <= '9'))
                return fail("malformed number: no digit in the exponent");
            while (pos_ < text_.size() && text_[pos_] >= '0' && text_[pos_] <= '9')
                ++pos_;
        }
        const std::string token = text_.substr(start, pos_ - start);
        errno = 0;
        char* end = nullptr;
        const double value = std::strtod(token.c_str(), &end);
        if (end != token.c_str() + token.size())
            return fail("malformed number '" + token + "'");
        out->type = Type::Number;
        out->number = value;  // overflow gives +-inf, which the metadata checks refuse
        out->integral = integral;
        return true;
    }

    const std::string& text_;
    size_t pos_ = 0;
    std::string message_;
};

} // namespace

const Value* Value::member(const std::string& key) const
{
    if (type != Type::Object)
        return nullptr;
    for (const auto& m : members)
        if (m.first == key)
            return &m.second;
    return nullptr;
}

const char* type_name(Type type)
{
    switch (type) {
    case Type::Null: return "null";
    case Type::Bool: return "a boolean";
    case Type::Number: return "a number";
    case Type::String: return "a string";
    case Type::Array: return "an array";
    case Type::Object: return "an object";
    }
    return "?";
}

bool parse(const std::string& text, Value* out, std::string* error)
{
    *out = Value();
    Parser parser(text);
    return parser.parse_document(out, error);
}

} // namespace json
} // namespace plenoptic
