// SPDX-License-Identifier: AGPL-3.0-or-later
// The plenoptic camera's keywords, in one table: one row per keyword and block it is written in
// (word, block, how its value is read, the check the value must pass, where it is stored, its
// default, a one-line description). The parser (parse_plenoptic.cpp) reads every block of
// `camera { plenoptic ... }` through this table and names its rows in the "allowed" list of an
// unknown keyword's error; tests/docs/test_keyword_table.py compares it with the keyword tables of
// docs/specification.md ("### Keywords"), so a keyword cannot be parsed and undocumented, or the
// reverse. A new keyword is one row in plenoptic_keywords.cpp (and one in the specification).
//
// No POV-Ray type here: tests/docs/plenoptic_keyword_table.cpp lists the table as text.

#ifndef POVRAY_GLUE_PLENOPTIC_KEYWORDS_H
#define POVRAY_GLUE_PLENOPTIC_KEYWORDS_H

#include <string>
#include <vector>

#include "povray_glue/plenoptic_setup.h"

namespace plenoptic {

// Where a keyword is written: the blocks of the specification's tables.
enum class KeywordBlock {
    None,            // (a row that opens no block)
    Camera,          // directly inside camera { plenoptic ... }
    MainLens,        // main_lens { }
    Distortion,      // main_lens { distortion { } }
    Prescription,    // main_lens { prescription { } }
    Surface,         // prescription { surface { } }
    Stop,            // prescription { stop { } }
    MicrolensArray,  // microlens_array { }
    Microlens,       // microlens_array { lens { } }: refracting microlenses
    MicrolensSurface,  // microlens_array { lens { surface { } } }
    Sensor,          // sensor { }
    WhiteImage,      // the modifiers read right after the camera's white_image
    Diffraction,     // the modifiers read right after the camera's diffraction
    Spectral,        // the modifiers read right after the camera's spectral N
    Errors           // microlens_array { errors { } }
};

// How the parser reads what follows the keyword.
enum class KeywordValue {
    Flag,      // nothing
    Number,    // a float expression
    Vector2,   // <a, b> (a float gives both)
    Vector3,   // <a, b, c>
    Vector6,   // <a, b, c, d, e, f>: six numbers in angle brackets (read into the list)
    OnOff,     // an optional float, 0 off and anything else (or none, or a keyword next) on; then
               // the modifiers of the block the row opens
    Word,      // one of the row's words, read by its text (not a string, not an identifier's value)
    String,    // a string: the name of a lens file, read into the main lens's prescription
    ResponseFile,  // a string: the name of a spectral response table, read into `response`
    Block,     // { } holding the keywords of the block the row opens
    Samples,   // N, or MIN, MAX
    FNumbers,  // N, or <N1, ..., Nk>
    FloatList, // <a, b, ...>: 1 to LensSurface::kMaxAspheric numbers in angle brackets (read into the list)
    NumberPair,  // a float, then optionally (after an optional comma) a second one: values[0], values[1] (0 when absent)
    LensTable  // a string: the name of a lens table (array/lens_errors.h), read into `lens_table`
};

// Keywords a block takes one of (or a keyword it takes once): the second is refused.
enum class KeywordGroup { None, MainLensKind, LensSource, Distortion, Grid, MicrolensKind, ArrayRotate, ArrayTranslate,
                          ArrayErrors, MicrolensSurface };

// A value as the parser read it, handed to the row's store.
struct KeywordRead {
    double values[3] = {0, 0, 0};  // Number: [0]; Vector2, Vector3: the components; OnOff: 1 on, 0 off;
                                   // Word: the index of the word; Samples: N (or MIN, MAX)
    std::vector<double> list;      // FNumbers, Vector6, FloatList: the values
    std::string text;              // String: the string
    Prescription prescription;     // String: the surfaces of the lens file it names
    SpectralResponse response;     // ResponseFile: the table it names
    std::shared_ptr<const std::vector<LensTableRow>> lens_table;  // LensTable: the rows of the table it names
    long line = 0;                 // where the keyword is written
    long column = 0;
    long long offset = 0;
};

// "" when the value is fine, else the message (named with the row's label); see camera/params.h.
typedef std::string (*KeywordCheck)(const char *label, double value);
// Writes the value into the camera being parsed (a Block row: starts its block).
typedef void (*KeywordStore)(CameraSetup& setup, const KeywordRead& read);
// A Word row's words: the index-th, nullptr past the last.
typedef const char *(*KeywordWordAt)(int index);

struct Keyword {
    Keyword(const char *word_, KeywordBlock block_, KeywordValue value_, const char *default_text_, const char *doc_,
            KeywordStore store_)
        : word(word_), block(block_), value(value_), default_text(default_text_), doc(doc_), store(store_) {}

    const char *word;
    KeywordBlock block;
    KeywordValue value;
    const char *default_text;  // as the specification's "default" column says it; "" when none
    const char *doc;           // one line
    KeywordStore store;
    KeywordCheck check = nullptr;              // Number, Vector, Samples, FNumbers: each value, after the finite check
                                               // (Vector6: finite only)
    const char *label = nullptr;               // how value errors name the keyword; nullptr: the word
    const char *listed = nullptr;              // how the block's "allowed" list names it; nullptr: the word
    bool reserved = false;                     // one of POV-Ray's reserved words (recognised by its token);
                                               // else a word only here, recognised by its text
    KeywordGroup group = KeywordGroup::None;
    bool needed = false;                       // the block is refused at its } without it (checked by the parser)
    KeywordBlock opens = KeywordBlock::None;   // Block: the block inside; another kind: the block of its modifiers
    KeywordWordAt word_at = nullptr;           // Word: the words allowed

    // Setters for the table's rows.
    Keyword& checked(KeywordCheck c) { check = c; return *this; }
    Keyword& labelled(const char *l) { label = l; return *this; }
    Keyword& listed_as(const char *l) { listed = l; return *this; }
    Keyword& reserved_word() { reserved = true; return *this; }
    Keyword& in_group(KeywordGroup g) { group = g; return *this; }
    Keyword& needed_in_block() { needed = true; return *this; }
    Keyword& opening(KeywordBlock b) { opens = b; return *this; }
    Keyword& words(KeywordWordAt w) { word_at = w; return *this; }

    const char *value_label() const { return label != nullptr ? label : word; }
};

struct KeywordBlockInfo {
    KeywordBlock block;
    const char *name;          // as the specification's tables name it: camera, main_lens, ...
    const char *in_messages;   // as errors name it: "plenoptic camera", "main_lens", ...
    const char *allowed_tail;  // what the "allowed" list adds after the rows, or nullptr
    int max_modifiers;         // a block of modifiers: how many are read after its keyword (0: any number)
};

// Every row, the rows of a block in the order its "allowed" list names them.
const std::vector<Keyword>& keyword_table();
const KeywordBlockInfo& keyword_block(KeywordBlock block);
// The row of `word` in `block`, or nullptr.
const Keyword *find_keyword(KeywordBlock block, const char *word);
// The row of `word` in the first block that has it, or nullptr: whether the word is the camera's.
const Keyword *find_keyword(const char *word);
// The list that follows "allowed: " when a block meets a word that is not its keyword.
std::string allowed_keywords(KeywordBlock block);
// A group's refusal ("main_lens takes one of thin_lens, pinhole or thick_lens, not several").
const char *keyword_group_message(KeywordGroup group);
// The block's needed keywords for its refusal: "radius, thickness, ior and aperture"; "" when none.
std::string needed_keywords(KeywordBlock block);
// A Word row's words joined by `separator`.
std::string keyword_words(const Keyword& keyword, const char *separator);
// The kind's name in the listing: flag, number, vector2, ...
const char *keyword_value_name(KeywordValue value);

} // namespace plenoptic

#endif
