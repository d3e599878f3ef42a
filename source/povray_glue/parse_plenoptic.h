// SPDX-License-Identifier: AGPL-3.0-or-later
// The plenoptic camera's parser, as POV-Ray's Parse_Camera calls it (patch 0003). The parser
// itself is the class PlenopticParser (parse_plenoptic.cpp), which POV-Ray's Parser names its
// friend: that one line is all the patch adds to parse.h.

#ifndef POVRAY_GLUE_PARSE_PLENOPTIC_H
#define POVRAY_GLUE_PARSE_PLENOPTIC_H

namespace pov
{

class Parser;
class Camera;

// Reads the body of `camera { plenoptic ... }` after the word `plenoptic`, up to the camera's
// closing brace (left for Parse_Camera), into camera.Plenoptic.
void Parse_Plenoptic_Camera(Parser& parser, Camera& camera);

// Once Parse_Camera has resolved the placement (look_at, sky, transforms): refuses a frame
// that does not span 3-D space, naming the placement keyword that completed it.
void Plenoptic_Check_Placement(Parser& parser, const Camera& camera);

}

#endif
