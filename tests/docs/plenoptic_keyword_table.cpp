// SPDX-License-Identifier: AGPL-3.0-or-later
// plenoptic-keyword-table: lists the plenoptic camera's keyword table, the one the parser reads
// every block through (source/povray_glue/plenoptic_keywords.h), for the tests that compare it
// with the specification (tests/docs/test_keyword_table.py) and that use its words as
// identifiers (tests/compat/test_camera_words.py).
//
//   plenoptic-keyword-table            one row per line, tab-separated, after a header line:
//                                      word, block, value, opens, reserved, default, doc
//   plenoptic-keyword-table --allowed  per block: block, the "allowed" list of its errors

#include <cstdio>
#include <cstring>

#include "povray_glue/plenoptic_keywords.h"

int main(int argc, char **argv)
{
    using namespace plenoptic;
    if (argc == 2 && std::strcmp(argv[1], "--allowed") == 0)
    {
        const KeywordBlock blocks[] = {KeywordBlock::Camera, KeywordBlock::MainLens, KeywordBlock::Distortion,
                                       KeywordBlock::Prescription, KeywordBlock::Surface, KeywordBlock::Stop,
                                       KeywordBlock::MicrolensArray, KeywordBlock::Sensor};
        for (KeywordBlock block : blocks)
            std::printf("%s\t%s\n", keyword_block(block).name, allowed_keywords(block).c_str());
        return 0;
    }
    if (argc != 1)
    {
        std::fprintf(stderr, "usage: %s [--allowed]\n", argv[0]);
        return 2;
    }
    std::printf("word\tblock\tvalue\topens\treserved\tdefault\tdoc\n");
    for (const Keyword& keyword : keyword_table())
        std::printf("%s\t%s\t%s\t%s\t%s\t%s\t%s\n", keyword.word, keyword_block(keyword.block).name,
                    keyword_value_name(keyword.value), keyword_block(keyword.opens).name,
                    keyword.reserved ? "yes" : "no", keyword.default_text, keyword.doc);
    return 0;
}
