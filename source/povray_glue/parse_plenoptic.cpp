// SPDX-License-Identifier: AGPL-3.0-or-later
// Parser for the body of `camera { plenoptic ... }`. Every value is checked while its
// token is current, so POV-Ray's error names the file and line; cross-field checks run
// when a block's closing brace is read. The optics themselves live in source/plenoptic/.
//
// Every block is read through the keyword table (plenoptic_keywords.h): a row says which block
// takes the word, how its value is read and checked and where it is stored; the parser reads
// the value by its kind and names the block's rows when it meets a word that is not one.
//
// Only `plenoptic` is a reserved word of the scene language (patch 0001). Every other word
// of the camera is recognised here, where the camera's parser expects a keyword, from the
// token's text: to the rest of the language it is an ordinary identifier, so a scene that
// declares `pitch` or `sensor` parses as with stock POV-Ray, and a declared identifier of
// the same name can even serve as a value (`pitch pitch / 100`). New keywords go into the
// table, never into POV-Ray's reserved-word table; the table's few rows that are POV-Ray's
// own reserved words (aperture, rotate, ...) are marked so and recognised by their tokens.

#include "povray_glue/parse_plenoptic.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include <sys/stat.h>

#include "backend/frame.h"
#include "backend/parser/parse.h"  // and reswords.h (no include guard of its own)
#include "backend/scene/camera.h"
#include "backend/support/fileutil.h"
#include "plenoptic/sensor/diffraction.h"
#include "plenoptic/camera/light_check.h"
#include "plenoptic/camera/radiometry.h"
#include "plenoptic/core/setup_progress.h"
#include "povray_glue/plenoptic_keywords.h"
#include "povray_glue/plenoptic_setup.h"

#include "base/povdebug.h"

namespace pov
{

namespace
{

using plenoptic::Keyword;
using plenoptic::KeywordBlock;
using plenoptic::KeywordCheck;
using plenoptic::KeywordRead;
using plenoptic::KeywordValue;

// Most bytes read from a lens file: a prescription is a few hundred; this bounds a wrong file
// (a device, an image) to a prompt refusal.
const size_t kMaxLensFileBytes = 1 << 20;
// A lens table has a row per lens: millions of lenses fit.
const size_t kMaxLensTableBytes = size_t(1) << 28;
// A traced lens with this many surfaces or more prints its setup's progress (about a second's work for 100).
const size_t kSetupProgressSurfaces = 100;

bool Finite(const VECTOR v) { return std::isfinite(v[X]) && std::isfinite(v[Y]) && std::isfinite(v[Z]); }

// Parse_Camera marks an unset look_at, up or right with HUGE_VAL in every component.
bool Finite_Or_Unset(const VECTOR v) { return Finite(v) || (v[X] == HUGE_VAL && v[Y] == HUGE_VAL && v[Z] == HUGE_VAL); }

// A row of the table that is one of POV-Ray's reserved words, with its token.
struct ReservedKeyword { TOKEN token; const char *word; };

// The table's reserved words, found in POV-Ray's reserved-word table once; `mistake` names a row
// marked otherwise than POV-Ray has it (the table's error).
struct ReservedKeywords
{
	std::vector<ReservedKeyword> words;
	std::string mistake;
};

ReservedKeywords Find_Reserved_Keywords()
{
	ReservedKeywords reserved;
	for (const Keyword& keyword : plenoptic::keyword_table())
	{
		bool found = false;
		for (int i = 0; i < LAST_TOKEN; i++)
			if (Reserved_Words[i].Token_Name != NULL && std::strcmp(Reserved_Words[i].Token_Name, keyword.word) == 0)
			{
				found = true;
				const ReservedKeyword word = {Reserved_Words[i].Token_Number, keyword.word};
				if (keyword.reserved)
					reserved.words.push_back(word);
			}
		if (found != keyword.reserved && reserved.mistake.empty())
			reserved.mistake = std::string("the keyword table marks '") + keyword.word + "' as " +
			                   (keyword.reserved ? "" : "not ") + "one of POV-Ray's reserved words, which it is" +
			                   (found ? "" : " not");
	}
	return reserved;
}

const ReservedKeywords& Reserved_Keywords()
{
	static const ReservedKeywords reserved = Find_Reserved_Keywords();
	return reserved;
}

}

// Reads the camera through the keyword table. POV-Ray's Parser names this class its friend
// (patch 0003), so it reads tokens with the Parser's own functions.
class PlenopticParser
{
	public:
		explicit PlenopticParser(Parser& parser) : p(parser), Token(parser.Token) {}
		void Parse_Camera(Camera& camera);
		void Check_Placement(const Camera& camera);

	private:
		typedef pov_base::ITextStream::FilePos FilePos;
		// A keyword a block has read, and where: a block's groups, needed keywords and positions.
		struct Given { const Keyword *keyword; FilePos position; int column; };
		typedef std::vector<Given> BlockState;

		Parser& p;
		Parser::Token_Struct& Token;
		plenoptic::CameraSetup *setup = nullptr;
		Camera *camera = nullptr;

		const char *Word_Here();
		const Keyword *Keyword_Here(KeywordBlock block);
		bool Closing() const { return Token.Token_Id == RIGHT_CURLY_TOKEN; }
		bool Keyword_Follows();
		void Parse_Keywords(KeywordBlock block);
		void Parse_Keyword(const Keyword& keyword, BlockState& state);
		void Parse_Modifiers(KeywordBlock block);
		void Parse_Word(const Keyword& keyword, KeywordRead& read);
		std::string Read_Named_File(const char *keyword, const char *kind, bool lenses_folder, std::string *file,
		                            size_t max_bytes = kMaxLensFileBytes);
		void Parse_Lens_File(KeywordRead& read);
		void Parse_Response_File(KeywordRead& read);
		void Parse_Lens_Table(KeywordRead& read);
		void Parse_Number_Pair(const Keyword& keyword, KeywordRead& read);
		void Parse_Samples(const Keyword& keyword, KeywordRead& read);
		void Parse_F_Numbers(const Keyword& keyword, KeywordRead& read);
		void Parse_Vector6(const Keyword& keyword, KeywordRead& read);
		void Parse_Float_List(const Keyword& keyword, KeywordRead& read);
		bool Parse_Bracket_Floats(size_t most, std::vector<DBL>* values);
		void Parse_Camera_Modifier();
		void Parse_Placement();
		void Close_Block(KeywordBlock block, const BlockState& state);
		void Close_Main_Lens(const BlockState& state);
		void Close_Prescription();
		void Close_Camera();
		DBL Float(const char *label, KeywordCheck check);
		void Values(const char *label, DBL *values, int count, KeywordCheck check);
		void Check(const std::string& message);
		void Check_At(const std::string& message, const FilePos& position, int column);
		void Unknown(KeywordBlock block);
};

void Parse_Plenoptic_Camera(Parser& parser, Camera& camera)
{
	PlenopticParser(parser).Parse_Camera(camera);
}

void Plenoptic_Check_Placement(Parser& parser, const Camera& camera)
{
	PlenopticParser(parser).Check_Placement(camera);
}

// Raises a parse error at the current token when a check returned a message.
void PlenopticParser::Check(const std::string& message)
{
	if (!message.empty())
		p.Error("plenoptic camera: %s.", message.c_str());
}

// Value errors point at the keyword: once its value is read, POV-Ray's current token is
// already the next one, which may sit on a later line.
void PlenopticParser::Check_At(const std::string& message, const FilePos& position, int column)
{
	if (message.empty())
		return;
	const std::string text = "plenoptic camera: " + message + ".";
	if (Token.FileHandle != NULL)
		p.messageFactory.ErrorAt(POV_EXCEPTION(kParseErr, text.c_str()), Token.FileHandle->name(), position.lineno,
		                         column, position.offset, "%s", text.c_str());
	else
		p.Error("%s", text.c_str());
}

// An unknown keyword inside one of our blocks is an error that names it and what is allowed.
void PlenopticParser::Unknown(KeywordBlock block)
{
	const char *name = plenoptic::keyword_block(block).in_messages;
	const std::string allowed = plenoptic::allowed_keywords(block);
	if (Token.End_Of_File || Token.Token_Id == END_OF_FILE_TOKEN)
		p.Error("plenoptic camera: the file ends inside %s, before its closing '}'; allowed: %s.", name, allowed.c_str());
	const char *found = (Token.Token_String != NULL && Token.Token_String[0] != '\0') ? Token.Token_String : p.Get_Token_String(Token.Token_Id);
	p.Error("plenoptic camera: '%s' is not a %s keyword; allowed: %s.", found, name, allowed.c_str());
}

// The keyword of the table the current token stands for, whatever block takes it, or NULL. A
// camera word arrives as an undeclared identifier, or as whatever the scene declared under that
// name (a float, an object, a macro parameter...): its text decides. A reserved word is known by
// its token (a float function's, such as seed, by Function_Id). A string literal never is a
// keyword, and at the end of the file the token's text is stale.
const char *PlenopticParser::Word_Here()
{
	const ReservedKeywords& reserved = Reserved_Keywords();
	if (!reserved.mistake.empty())
		p.Error("plenoptic camera: internal error: %s.", reserved.mistake.c_str());
	for (const ReservedKeyword& word : reserved.words)
		if (Token.Token_Id == word.token || (Token.Token_Id == FLOAT_FUNCT_TOKEN && Token.Function_Id == word.token))
			return word.word;
	if (Token.End_Of_File || Token.Token_Id == END_OF_FILE_TOKEN || Token.Token_Id == STRING_LITERAL_TOKEN ||
	    Token.Token_String == NULL)
		return NULL;
	const Keyword *keyword = plenoptic::find_keyword(Token.Token_String);
	return (keyword != NULL && !keyword->reserved) ? keyword->word : NULL;
}

// The current token's row in `block`, or NULL.
const Keyword *PlenopticParser::Keyword_Here(KeywordBlock block)
{
	const char *word = Word_Here();
	return word != NULL ? plenoptic::find_keyword(block, word) : NULL;
}

// Before an optional value (depth_map [off], samples N [, MAX]): whether the next token is a
// keyword of the camera (or its closing brace), which is then not taken for the value even
// where the scene declared an identifier of that name.
bool PlenopticParser::Keyword_Follows()
{
	p.Get_Token();
	const bool keyword = Closing() || Word_Here() != NULL;
	p.Unget_Token();
	return keyword;
}

// The float after the current keyword, finite and passing `check` (which may be NULL).
DBL PlenopticParser::Float(const char *label, KeywordCheck check)
{
	const FilePos position = Token.Token_File_Pos;
	const int column = Token.Token_Col_No;
	DBL value = p.Parse_Float();
	Check_At(plenoptic::check_finite(label, value), position, column);
	if (check != NULL)
		Check_At(check(label, value), position, column);
	return value;
}

// The vector (count 2 or 3) after the current keyword, each component finite and passing `check`.
void PlenopticParser::Values(const char *label, DBL *values, int count, KeywordCheck check)
{
	const FilePos position = Token.Token_File_Pos;
	const int column = Token.Token_Col_No;
	VECTOR v;
	UV_VECT uv;
	if (count == 2)
		p.Parse_UV_Vect(uv);
	else
		p.Parse_Vector(v);
	for (int i = 0; i < count; i++)
	{
		values[i] = (count == 2) ? uv[i] : v[i];
		Check_At(plenoptic::check_finite(label, values[i]), position, column);
		if (check != NULL)
			Check_At(check(label, values[i]), position, column);
	}
}

// The keywords of `block` up to its closing brace, which is current when the block's checks
// run and when this returns.
void PlenopticParser::Parse_Keywords(KeywordBlock block)
{
	BlockState state;
	for (p.Get_Token(); !Closing(); p.Get_Token())
	{
		const Keyword *keyword = Keyword_Here(block);
		if (keyword != NULL)
			Parse_Keyword(*keyword, state);
		else if (block == KeywordBlock::Camera)
			Parse_Camera_Modifier();
		else
			Unknown(block);
	}
	Close_Block(block, state);
}

// One keyword (current) and its value, read as the row says and stored by the row.
void PlenopticParser::Parse_Keyword(const Keyword& keyword, BlockState& state)
{
	const Given given = {&keyword, Token.Token_File_Pos, Token.Token_Col_No};
	if (keyword.group != plenoptic::KeywordGroup::None)
		for (const Given& earlier : state)
			if (earlier.keyword->group == keyword.group)
				p.Error("plenoptic camera: %s.", plenoptic::keyword_group_message(keyword.group));
	state.push_back(given);

	KeywordRead read;
	read.line = given.position.lineno;
	read.column = given.column;
	read.offset = given.position.offset;
	switch (keyword.value)
	{
		case KeywordValue::Flag:
			break;
		case KeywordValue::Number:
			read.values[0] = Float(keyword.value_label(), keyword.check);
			break;
		case KeywordValue::Vector2:
		case KeywordValue::Vector3:
			Values(keyword.value_label(), read.values, keyword.value == KeywordValue::Vector2 ? 2 : 3, keyword.check);
			break;
		case KeywordValue::OnOff:
			read.values[0] = (Keyword_Follows() || ((int)p.Allow_Float(1.0) != 0)) ? 1 : 0;
			break;
		case KeywordValue::Word:
			Parse_Word(keyword, read);
			break;
		case KeywordValue::String:
			Parse_Lens_File(read);
			break;
		case KeywordValue::ResponseFile:
			Parse_Response_File(read);
			break;
		case KeywordValue::Samples:
			Parse_Samples(keyword, read);
			break;
		case KeywordValue::FNumbers:
			Parse_F_Numbers(keyword, read);
			break;
		case KeywordValue::Vector6:
			Parse_Vector6(keyword, read);
			break;
		case KeywordValue::FloatList:
			Parse_Float_List(keyword, read);
			break;
		case KeywordValue::NumberPair:
			Parse_Number_Pair(keyword, read);
			break;
		case KeywordValue::LensTable:
			Parse_Lens_Table(read);
			break;
		case KeywordValue::Block:
			// The store starts the block; its keywords follow in braces.
			keyword.store(*setup, read);
			p.Parse_Begin();
			Parse_Keywords(keyword.opens);
			p.Unget_Token();
			p.Parse_End();
			return;
	}
	keyword.store(*setup, read);
	if (keyword.opens != KeywordBlock::None)
		Parse_Modifiers(keyword.opens);
}

// The modifiers after white_image or diffraction: as many as follow (at most the block's number).
void PlenopticParser::Parse_Modifiers(KeywordBlock block)
{
	const int most = plenoptic::keyword_block(block).max_modifiers;
	BlockState state;
	for (int n = 0; most == 0 || n < most; n++)
	{
		p.Get_Token();
		const Keyword *modifier = Keyword_Here(block);
		if (modifier == NULL)
		{
			p.Unget_Token();
			break;
		}
		Parse_Keyword(*modifier, state);
	}
}

// bayer rggb, radiometry flat: a word of the row's, read by its text as the camera's keywords are.
void PlenopticParser::Parse_Word(const Keyword& keyword, KeywordRead& read)
{
	p.Get_Token();
	const char *text = (Token.Token_Id != STRING_LITERAL_TOKEN && !Token.End_Of_File) ? Token.Token_String : NULL;
	int found = -1;
	for (int i = 0; text != NULL && keyword.word_at(i) != NULL; i++)
		if (std::strcmp(text, keyword.word_at(i)) == 0)
			found = i;
	if (found < 0)
		p.Error("plenoptic camera: %s takes one of %s, not '%s'.", keyword.word, plenoptic::keyword_words(keyword, ", ").c_str(),
		        text != NULL ? text : p.Get_Token_String(Token.Token_Id));
	read.values[0] = found;
}

// The text of the file a keyword names (the string that follows it), found as POV-Ray finds a file
// the scene reads (beside the scene, then the library paths) and, with lenses_folder, in the
// lenses/ folder installed with the program. *file is the name as written. Refused (naming the
// keyword, the file and `kind`, what the file should be): an empty name, a file not found, a
// directory, a file larger than kMaxLensFileBytes.
std::string PlenopticParser::Read_Named_File(const char *keyword, const char *kind, bool lenses_folder, std::string *file,
                                             size_t max_bytes)
{
	const FilePos position = Token.Token_File_Pos;
	const int column = Token.Token_Col_No;
	char *name = p.Parse_C_String(true);
	*file = name;
	POV_FREE(name);
	const std::string quoted = std::string(keyword) + " \"" + *file + "\"";
	if (file->empty())
		Check_At(std::string(keyword) + " \"\" names no file: give the name of " + kind, position, column);
	UCS2String found;
	IStream *stream = Locate_File(&p, p.sceneData, ASCIItoUCS2String(file->c_str()), POV_File_Text_User, found, false);
	if (stream == NULL && lenses_folder)
		stream = Locate_File(&p, p.sceneData, ASCIItoUCS2String(("lenses/" + *file).c_str()), POV_File_Text_User, found, false);
	if (stream == NULL)
		Check_At(quoted + " was not found beside the scene" +
		         (lenses_folder ? ", in the library paths (+L) or in the lenses folder installed with the program"
		                        : " or in the library paths (+L)"), position, column);
	// A directory opens, and reads as no bytes: say what it is rather than "no surface".
	struct stat status;
	const std::string path = UCS2toASCIIString(found);
	if (stat(path.c_str(), &status) == 0 && S_ISDIR(status.st_mode))
	{
		delete stream;
		Check_At(quoted + " names a directory (" + path + "), not " + kind, position, column);
	}
	std::string text;
	for (int c = stream->Read_Byte(); c != EOF && text.size() <= max_bytes; c = stream->Read_Byte())
		text.push_back((char)c);
	delete stream;
	if (text.size() > max_bytes)
		Check_At(quoted + " is larger than " + std::to_string(max_bytes) + " bytes: not " + kind, position, column);
	return text;
}

// lens_file "name": pbrt's lens-file format (lens/prescription.h), found as Read_Named_File says.
// Errors name the file and its row.
void PlenopticParser::Parse_Lens_File(KeywordRead& read)
{
	const FilePos position = Token.Token_File_Pos;
	const int column = Token.Token_Col_No;
	std::string file;
	const std::string text = Read_Named_File("lens_file", "a lens file (pbrt's format, one row per surface)", true, &file);
	const plenoptic::ParsedPrescription parsed = plenoptic::parse_lens_file(text);
	if (parsed.error.any())
		Check_At("lens_file \"" + file + "\"" + (parsed.error.line > 0 ? ", line " + std::to_string(parsed.error.line) : std::string()) +
		         ": " + parsed.error.message, position, column);
	read.prescription.surfaces = parsed.prescription.surfaces;
	read.text = file;
}

// lens_table "name": a microlens array's measured errors (array/lens_errors.h: a header naming k, l
// and the error columns, one row per lens), found beside the scene or in the library paths. Errors
// name the file and its row. The pitch (needed to bound the shifts) is the array's so far; the
// array's own checks refuse a table read before the pitch.
void PlenopticParser::Parse_Lens_Table(KeywordRead& read)
{
	const FilePos position = Token.Token_File_Pos;
	const int column = Token.Token_Col_No;
	std::string file;
	const std::string text = Read_Named_File("lens_table", "a lens table (k, l, dx_mm, dy_mm, ... per row)", false, &file,
	                                         kMaxLensTableBytes);
	const plenoptic::ArrayParams& array = setup->params.array;
	if (!array.has_pitch)
		Check_At("lens_table \"" + file + "\" must come after the array's pitch (the shifts are checked against it)",
		         position, column);
	plenoptic::ParsedLensTable table = plenoptic::parse_lens_table(text, array.pitch_mm);
	if (!table.error.empty())
		Check_At("lens_table \"" + file + "\", line " + std::to_string(table.error_line) + ": " + table.error, position,
		         column);
	read.lens_table = std::make_shared<const std::vector<plenoptic::LensTableRow>>(std::move(table.rows));
	read.text = file;
}

// spectral response_file "name": the sensor's tabulated sensitivities (sensor/spectral_response.h:
// wavelength_nm, r, g, b per row), found beside the scene or in the library paths. Errors name the
// file and its row.
void PlenopticParser::Parse_Response_File(KeywordRead& read)
{
	const FilePos position = Token.Token_File_Pos;
	const int column = Token.Token_Col_No;
	std::string file;
	const std::string text = Read_Named_File("response_file", "a spectral response table (wavelength_nm, r, g, b per row)",
	                                         false, &file);
	std::string error;
	int line = 0;
	read.response = plenoptic::parse_response_table(text, &error, &line);
	if (error.empty())
		error = plenoptic::check_response(read.response);
	if (!error.empty())
		Check_At("spectral response_file \"" + file + "\"" + (line > 0 ? ", line " + std::to_string(line) : std::string()) +
		         ": " + error, position, column);
	read.response.file = file;
	read.text = file;
}

// samples N            a fixed count
// samples MIN, MAX     adaptive, stopping on confidence/variance as focal_blur does
void PlenopticParser::Parse_Samples(const Keyword& keyword, KeywordRead& read)
{
	const FilePos position = Token.Token_File_Pos;
	const int column = Token.Token_Col_No;
	DBL first = Float(keyword.value_label(), keyword.check);
	p.Parse_Comma();
	DBL second = Keyword_Follows() ? 0.0 : p.Allow_Float(0.0);
	read.values[0] = first;
	read.values[1] = second;
	if (second == 0.0)
		return;
	Check_At(plenoptic::check_adaptive_minimum(first), position, column);
	Check_At(plenoptic::check_finite("samples maximum", second), position, column);
	Check_At(keyword.check("samples maximum", second), position, column);
	if (first > second)
		Check_At("samples minimum (" + plenoptic::format_number(first) + ") must not be larger than the maximum (" +
		         plenoptic::format_number(second) + ")", position, column);
}

// A float, then optionally a second one (errors position S [, S_z]).
void PlenopticParser::Parse_Number_Pair(const Keyword& keyword, KeywordRead& read)
{
	const FilePos position = Token.Token_File_Pos;
	const int column = Token.Token_Col_No;
	read.values[0] = Float(keyword.value_label(), keyword.check);
	p.Parse_Comma();
	read.values[1] = Keyword_Follows() ? 0.0 : p.Allow_Float(0.0);
	Check_At(plenoptic::check_finite(keyword.value_label(), read.values[1]), position, column);
	if (keyword.check != NULL)
		Check_At(keyword.check(keyword.value_label(), read.values[1]), position, column);
}

// white_image f_numbers N | f_numbers <N1, ..., N16>: one f-number, or a list in angle brackets
// as a vector's components are read.
void PlenopticParser::Parse_F_Numbers(const Keyword& keyword, KeywordRead& read)
{
	const FilePos position = Token.Token_File_Pos;
	const int column = Token.Token_Col_No;
	std::vector<DBL> values;
	p.Get_Token();
	if (Token.Token_Id == LEFT_ANGLE_TOKEN)
	{
		if (!Parse_Bracket_Floats(plenoptic::kMaxWhiteImages, &values))
			Check_At("white_image f_numbers lists at most " + plenoptic::format_number(plenoptic::kMaxWhiteImages) +
			         " f-numbers, between '<' and '>'", position, column);
	}
	else
	{
		p.Unget_Token();
		values.push_back(p.Parse_Float());
	}
	for (size_t k = 0; k < values.size(); k++)
	{
		Check_At(plenoptic::check_finite(keyword.value_label(), values[k]), position, column);
		Check_At(keyword.check(keyword.value_label(), values[k]), position, column);
	}
	// A value listed twice is refused here; one the camera cannot take is found at the
	// camera's brace, and reported here too.
	plenoptic::WhiteImageRequest listed;
	listed.f_numbers = values;
	Check_At(plenoptic::repeated_white_f_number(listed), position, column);
	read.list = values;
}

// sellmeier <B1, B2, B3, C1, C2, C3>: six floats in angle brackets (POV-Ray's vectors hold at
// most five), each finite.
void PlenopticParser::Parse_Vector6(const Keyword& keyword, KeywordRead& read)
{
	const FilePos position = Token.Token_File_Pos;
	const int column = Token.Token_Col_No;
	const std::string six = std::string(keyword.value_label()) + " takes six numbers in angle brackets, " +
	                        (keyword.listed != NULL ? keyword.listed : keyword.word);
	p.Get_Token();
	if (Token.Token_Id != LEFT_ANGLE_TOKEN)
		Check_At(six, position, column);
	std::vector<DBL> values;
	const bool closed = Parse_Bracket_Floats(6, &values);
	if (values.size() != 6 || !closed)
		Check_At(six + "; found " + (values.size() == 6 ? std::string("more") : std::to_string(values.size())), position,
		         column);
	for (size_t k = 0; k < values.size(); k++)
		Check_At(plenoptic::check_finite(keyword.value_label(), values[k]), position, column);
	read.list = values;
}

// aspheric <a4, a6, ...>: 1 to LensSurface::kMaxAspheric floats in angle brackets, each finite.
void PlenopticParser::Parse_Float_List(const Keyword& keyword, KeywordRead& read)
{
	const FilePos position = Token.Token_File_Pos;
	const int column = Token.Token_Col_No;
	const size_t most = plenoptic::LensSurface::kMaxAspheric;
	const std::string what = std::string(keyword.value_label()) + " takes 1 to " + std::to_string(most) +
	                         " numbers in angle brackets, " + (keyword.listed != NULL ? keyword.listed : keyword.word);
	p.Get_Token();
	if (Token.Token_Id != LEFT_ANGLE_TOKEN)
		Check_At(what, position, column);
	std::vector<DBL> values;
	if (!Parse_Bracket_Floats(most, &values))
		Check_At(what + "; found more", position, column);
	for (size_t k = 0; k < values.size(); k++)
		Check_At(plenoptic::check_finite(keyword.value_label(), values[k]), position, column);
	read.list = values;
}

// The floats of an angle-bracket list whose '<' has just been read, separated by optional commas,
// up to its '>': true when the list closed within `most` values (false: more follow, unread).
bool PlenopticParser::Parse_Bracket_Floats(size_t most, std::vector<DBL>* values)
{
	for (;;)
	{
		values->push_back(p.Parse_Float());
		p.Parse_Comma();
		p.Get_Token();
		if (Token.Token_Id == RIGHT_ANGLE_TOKEN)
			return true;
		p.Unget_Token();
		if (values->size() >= most)
			return false;
	}
}

// At camera level, a token that is not one of the camera's keywords: refused, or POV-Ray's
// placement.
void PlenopticParser::Parse_Camera_Modifier()
{
	// A word of one of the blocks, out of its block (aperture, rotate and translate are also
	// POV-Ray's camera modifiers: below).
	if (Word_Here() != NULL && Token.Token_Id != APERTURE_TOKEN && Token.Token_Id != ROTATE_TOKEN &&
	    Token.Token_Id != TRANSLATE_TOKEN)
		Unknown(KeywordBlock::Camera);

	switch (Token.Token_Id)
	{
		// Focal blur and field-of-view modifiers would silently mean nothing here.
		case APERTURE_TOKEN: case BLUR_SAMPLES_TOKEN: case FOCAL_POINT_TOKEN: case BOKEH_TOKEN: case ANGLE_TOKEN:
			p.Error("plenoptic camera: '%s' does not apply to a plenoptic camera (the aperture, focus and field "
			        "of view come from main_lens { }, microlens_array { } and sensor { }).",
			        p.Get_Token_String(Token.Token_Id));
			break;

		case TNORMAL_TOKEN:
			p.Error("plenoptic camera: 'normal' (ray perturbation) is not supported by the plenoptic camera.");
			break;

		case PERSPECTIVE_TOKEN: case ORTHOGRAPHIC_TOKEN: case FISHEYE_TOKEN: case ULTRA_WIDE_ANGLE_TOKEN:
		case OMNIMAX_TOKEN: case PANORAMIC_TOKEN: case SPHERICAL_TOKEN: case CYLINDER_TOKEN: case MESH_CAMERA_TOKEN:
			p.Expectation_Error("plenoptic camera modifier");
			break;

		default:
			Parse_Placement();
	}
}

// POV-Ray's own camera modifiers (location, look_at, rotate, ...), read by its camera parser;
// then the placement must be finite and right, up, direction and sky non-zero.
void PlenopticParser::Parse_Placement()
{
	Camera& New = *camera;
	const FilePos position = Token.Token_File_Pos;
	const int column = Token.Token_Col_No;
	const TOKEN keyword = Token.Token_Id;
	p.Unget_Token();
	if (p.Parse_Camera_Mods(New) == false)
	{
		p.Get_Token();
		Unknown(KeywordBlock::Camera);
	}
	// Placement too must be finite (POV-Ray's stock cameras would render black).
	bool finite = Finite(New.Location) && Finite(New.Sky) && Finite(New.Direction) &&
	              Finite_Or_Unset(New.Look_At) && Finite_Or_Unset(New.Up) && Finite_Or_Unset(New.Right);
	for (int r = 0; r < 4 && New.Trans != NULL; r++)
		for (int c = 0; c < 4; c++)
			finite = finite && std::isfinite(New.Trans->matrix[r][c]) && std::isfinite(New.Trans->inverse[r][c]);
	if (!finite)
		Check_At(std::string("'") + p.Get_Token_String(keyword) + "' gives a value that is not a finite "
		         "number (NaN or infinite)", position, column);
	// A zero right, up or direction leaves the camera without a frame.
	const DBL *given = (keyword == RIGHT_TOKEN) ? New.Right : (keyword == UP_TOKEN) ? New.Up :
	                   (keyword == DIRECTION_TOKEN) ? New.Direction : (keyword == SKY_TOKEN) ? New.Sky : NULL;
	if (given != NULL && !(given[X] * given[X] + given[Y] * given[Y] + given[Z] * given[Z] > 0))
		Check_At(std::string("'") + p.Get_Token_String(keyword) + "' is a zero vector: the camera's "
		         "right, up, direction and sky must have a non-zero length", position, column);
	setup->last_placement.keyword = p.Get_Token_String(keyword);
	setup->last_placement.line = position.lineno;
	setup->last_placement.column = column;
	setup->last_placement.offset = position.offset;
}

// The checks at a block's closing brace (current): the block's needed keywords, then its
// cross-field checks.
void PlenopticParser::Close_Block(KeywordBlock block, const BlockState& state)
{
	for (const Keyword& keyword : plenoptic::keyword_table())
	{
		if (keyword.block != block || !keyword.needed)
			continue;
		bool given = false;
		for (const Given& g : state)
			given = given || g.keyword == &keyword;
		if (!given)
			p.Error("plenoptic camera: %s needs %s.", plenoptic::keyword_block(block).in_messages,
			        plenoptic::needed_keywords(block).c_str());
	}
	switch (block)
	{
		case KeywordBlock::Camera:
			Close_Camera();
			break;
		case KeywordBlock::MainLens:
			Close_Main_Lens(state);
			break;
		case KeywordBlock::Prescription:
			Close_Prescription();
			break;
		case KeywordBlock::MicrolensArray:
			Check(plenoptic::check_array(setup->params.array));
			break;
		case KeywordBlock::Sensor:
			Check(plenoptic::check_sensor(setup->params.sensor));
			break;
		default:
			break;
	}
}

void PlenopticParser::Close_Main_Lens(const BlockState& state)
{
	plenoptic::MainLensParams& lens = setup->params.main;
	// The iris turned by a multiple of 360 / blades is the same iris: the metadata keeps the turn in [0, 360 / blades).
	lens.blade_rotation_deg = plenoptic::reduced_blade_rotation(lens.blade_rotation_deg, lens.blades);
	// A real lens without thin_lens, pinhole or thick_lens is traced surface by surface.
	if (lens.type == plenoptic::MainLensType::None && lens.has_prescription)
		lens.type = plenoptic::MainLensType::Prescription;
	// The closing brace is current: cross-field errors point at the end of the block; a stop the
	// lens cannot deliver, at its (last) f_number or aperture.
	const Given *stop = NULL;
	for (const Given& given : state)
		if (std::strcmp(given.keyword->word, "f_number") == 0 || std::strcmp(given.keyword->word, "aperture") == 0)
			stop = &given;
	const std::string lens_message = plenoptic::check_main_lens(lens, setup->params.mm_per_unit);
	if (!lens_message.empty() && stop != NULL && lens_message == plenoptic::check_aperture_reach(lens, setup->params.mm_per_unit))
		Check_At(lens_message, stop->position, stop->column);
	Check(lens_message);
}

void PlenopticParser::Close_Prescription()
{
	const plenoptic::PrescriptionError error = plenoptic::check_prescription(setup->params.main.prescription);
	if (error.any())
	{
		FilePos position = Token.Token_File_Pos;
		position.lineno = error.line > 0 ? error.line : position.lineno;
		Check_At("prescription: " + error.message, position, error.line > 0 ? 1 : (int)Token.Token_Col_No);
	}
}

// The camera's closing brace is current for the checks across blocks; then the model is made.
void PlenopticParser::Close_Camera()
{
	plenoptic::CameraParams& params = setup->params;
	Check(plenoptic::check_camera(params));
	if (setup->white_image.given)
	{
		// An f-number the camera cannot take is refused at the f_numbers keyword; the rest here.
		const std::string white = plenoptic::check_white_image(setup->white_image, params);
		if (!white.empty() && !setup->white_f_numbers.keyword.empty() &&
		    white == plenoptic::check_white_image_f_numbers(setup->white_image, params))
		{
			FilePos position;
			position.lineno = setup->white_f_numbers.line;
			position.offset = setup->white_f_numbers.offset;
			Check_At(white, position, (int)setup->white_f_numbers.column);
		}
		Check(white);
	}
	Check(plenoptic::check_diffraction(params.diffraction, params));
	// A traced lens's tables cost a fixed number of traces, each linear in its surfaces: a lens of
	// 2,000 surfaces sets up for tens of seconds. Ctrl-C stops the parse there as anywhere (the
	// parser's Cooperate throws), and a lens of many surfaces says how far on stderr.
	const size_t surfaces = params.main.prescription.surfaces.size();
	std::string last_step;
	int last_tenth = -1;
	Parser& parser = p;
	plenoptic::ScopedSetupReporter reporter([&](const char *step, int done, int total)
	{
		parser.Cooperate();
		if (surfaces < kSetupProgressSurfaces)
			return;
		const int tenth = total > 0 ? std::min(10, done * 10 / total) : 10;
		if (tenth == last_tenth && last_step == step)
			return;
		last_tenth = tenth;
		last_step = step;
		std::fprintf(stderr, "plenoptic camera: setting up a lens of %zu surfaces: %s %d %%\n", surfaces, step, 10 * tenth);
	});
	setup->model = plenoptic::make_camera(params);
	Check(plenoptic::check_diffraction_size(setup->model, params.diffraction));
	for (size_t k = 0; k < setup->white_image.f_numbers.size() && params.diffraction.given; k++)
		Check(plenoptic::check_diffraction_size(
			plenoptic::make_camera(plenoptic::at_f_number(params, setup->white_image.f_numbers[k])), params.diffraction));
}

void PlenopticParser::Parse_Camera(Camera& New)
{
	POV_TR1_NAMESPACE::shared_ptr<plenoptic::CameraSetup> made(new plenoptic::CameraSetup());
	setup = made.get();
	camera = &New;
	// A camera declared earlier and modified here keeps its plenoptic parameters.
	if (New.Plenoptic)
	{
		setup->params = New.Plenoptic->params;
		setup->depth_map = New.Plenoptic->depth_map;
		setup->microimage_centres = New.Plenoptic->microimage_centres;
		setup->white_image = New.Plenoptic->white_image;
	}
	Parse_Keywords(KeywordBlock::Camera);
	p.Unget_Token();
	std::vector<std::string> warnings = plenoptic::warnings(setup->model);
	const std::string dark = plenoptic::dark_image_warning(setup->model);
	if (!dark.empty())
		warnings.push_back(dark);
	for (size_t i = 0; i < warnings.size(); i++)
		p.Warning(0, "plenoptic camera: %s", warnings[i].c_str());
	New.Plenoptic = made;
}

// Called by Parse_Camera once POV-Ray has resolved the placement (look_at, sky, transforms):
// the frame the camera will use must span 3-D space. The error names the last placement
// keyword, the one that completed the degenerate frame.
void PlenopticParser::Check_Placement(const Camera& Cam)
{
	const std::string message = plenoptic::check_placement(Cam.Right, Cam.Up, Cam.Direction);
	if (message.empty() || !Cam.Plenoptic)
	{
		Check(message);
		return;
	}
	const plenoptic::CameraSetup::KeywordSource& source = Cam.Plenoptic->last_placement;
	if (source.keyword.empty())
		Check(message);
	FilePos position;
	position.lineno = source.line;
	position.offset = source.offset;
	Check_At(message + " (after '" + source.keyword + "')", position, (int)source.column);
}

}
