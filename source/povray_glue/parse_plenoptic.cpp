// SPDX-License-Identifier: AGPL-3.0-or-later
// Parser for the body of `camera { plenoptic ... }`. Every value is checked while its
// token is current, so POV-Ray's error names the file and line; cross-field checks run
// when a block's closing brace is read. The optics themselves live in source/plenoptic/.
//
// Only `plenoptic` is a reserved word of the scene language (patch 0001). Every other word
// of the camera is recognised here, where the camera's parser expects a keyword, from the
// token's text: to the rest of the language it is an ordinary identifier, so a scene that
// declares `pitch` or `sensor` parses as with stock POV-Ray, and a declared identifier of
// the same name can even serve as a value (`pitch pitch / 100`). New keywords go into
// kContextWords below, never into POV-Ray's reserved-word table.

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include <sys/stat.h>

#include "backend/frame.h"
#include "backend/parser/parse.h"
#include "backend/scene/camera.h"
#include "backend/support/fileutil.h"
#include "plenoptic/sensor/diffraction.h"
#include "plenoptic/camera/light_check.h"
#include "plenoptic/camera/radiometry.h"
#include "plenoptic/core/setup_progress.h"
#include "povray_glue/plenoptic_setup.h"

#include "base/povdebug.h"

namespace pov
{

namespace
{

const char *kPlenopticKeywords =
	"main_lens { }, microlens_array { }, sensor { }, mm_per_unit, samples, confidence, variance, depth_map, "
	"microimage_centres, white_image, radiometry, diffraction, "
	"and the placement keywords of every camera (location, look_at, sky, right, up, direction, rotate, "
	"translate, scale, matrix, transform)";
const char *kMainLensKeywords = "thin_lens, pinhole, thick_lens, lens_file, prescription { }, focal_length, f_number, aperture, "
	"focus_distance, distance, blades, blade_rotation, distortion { }";
const char *kDistortionKeywords = "radial <k1, k2, k3>, tangential <p1, p2>";
const char *kPrescriptionKeywords = "surface { }, stop { }";
const char *kSurfaceKeywords = "radius, thickness, ior, aperture";
const char *kStopKeywords = "thickness, aperture";
const char *kArrayKeywords = "hexagonal, rectangular, pitch, focal_length, focal_lengths, pinhole, distance, rotate, translate";
const char *kSensorKeywords = "pixel_size, offset, angular_response, and the read-out to the raw: bayer rggb|bggr|grbg|gbrg, bit_depth, "
	"full_well, exposure, read_noise, dark_current, exposure_time, prnu, dsnu, black_level, seed";
const char *kBayerPatterns = "rggb, bggr, grbg, gbrg";
const char *kRadiometries = "flat, irradiance";

// A keyword as the camera's blocks see it, whether it is one of the camera's own words or a
// stock reserved word that the blocks read too.
enum class Word
{
	None,         // no keyword of the camera's blocks: a placement modifier, a value, an error
	CloseBlock,   // }
	// the camera's own words: identifiers everywhere else
	MainLens, MicrolensArray, Sensor, ThinLens, Pinhole, FocalLength, FocalLengths, FNumber,
	FocusDistance, Hexagonal, Rectangular, Pitch, PixelSize, DepthMap,
	ThickLens, LensFile, Prescription, Surface, Stop, Blades, BladeRotation, Distortion, Tangential,
	MicroimageCentres, Bayer, BitDepth, FullWell, Exposure, ReadNoise, DarkCurrent, ExposureTime, Prnu,
	Dsnu, BlackLevel, WhiteImage, FNumbers, NoiseFree, Radiometry, Diffraction, Wavelengths, AngularResponse,
	// stock reserved words
	MmPerUnit, Aperture, Distance, Offset, Rotate, Translate, Samples, Confidence, Variance,
	Radius, Thickness, Ior, Radial, Seed
};

struct ContextWord { const char *text; Word word; };
const ContextWord kContextWords[] = {
	{"main_lens", Word::MainLens}, {"microlens_array", Word::MicrolensArray}, {"sensor", Word::Sensor},
	{"thin_lens", Word::ThinLens}, {"pinhole", Word::Pinhole}, {"focal_length", Word::FocalLength},
	{"focal_lengths", Word::FocalLengths}, {"f_number", Word::FNumber}, {"focus_distance", Word::FocusDistance},
	{"hexagonal", Word::Hexagonal}, {"rectangular", Word::Rectangular}, {"pitch", Word::Pitch},
	{"pixel_size", Word::PixelSize}, {"depth_map", Word::DepthMap}, {"thick_lens", Word::ThickLens},
	{"lens_file", Word::LensFile}, {"prescription", Word::Prescription}, {"surface", Word::Surface},
	{"stop", Word::Stop}, {"blades", Word::Blades}, {"blade_rotation", Word::BladeRotation},
	{"distortion", Word::Distortion}, {"tangential", Word::Tangential},
	{"microimage_centres", Word::MicroimageCentres}, {"bayer", Word::Bayer}, {"bit_depth", Word::BitDepth},
	{"full_well", Word::FullWell}, {"exposure", Word::Exposure}, {"read_noise", Word::ReadNoise},
	{"dark_current", Word::DarkCurrent}, {"exposure_time", Word::ExposureTime}, {"prnu", Word::Prnu},
	{"dsnu", Word::Dsnu}, {"black_level", Word::BlackLevel}, {"white_image", Word::WhiteImage},
	{"f_numbers", Word::FNumbers}, {"noise_free", Word::NoiseFree}, {"radiometry", Word::Radiometry},
	{"diffraction", Word::Diffraction}, {"wavelengths", Word::Wavelengths},
	{"angular_response", Word::AngularResponse}
};

struct StockWord { TOKEN token; Word word; };
const StockWord kStockWords[] = {
	{RIGHT_CURLY_TOKEN, Word::CloseBlock}, {MM_PER_UNIT_TOKEN, Word::MmPerUnit}, {APERTURE_TOKEN, Word::Aperture},
	{DISTANCE_TOKEN, Word::Distance}, {OFFSET_TOKEN, Word::Offset}, {ROTATE_TOKEN, Word::Rotate},
	{TRANSLATE_TOKEN, Word::Translate}, {SAMPLES_TOKEN, Word::Samples}, {CONFIDENCE_TOKEN, Word::Confidence},
	{VARIANCE_TOKEN, Word::Variance}, {RADIUS_TOKEN, Word::Radius}, {THICKNESS_TOKEN, Word::Thickness},
	{IOR_TOKEN, Word::Ior}, {RADIAL_TOKEN, Word::Radial}
};

// The keyword the current token stands for. A camera word arrives as an undeclared
// identifier, or as whatever the scene declared under that name (a float, an object, a
// macro parameter...): its text decides. A string literal never is a keyword, and at the end
// of the file the token's text is stale.
Word Word_Of(const Parser::Token_Struct& token)
{
	for (size_t i = 0; i < sizeof(kStockWords) / sizeof(kStockWords[0]); i++)
		if (token.Token_Id == kStockWords[i].token)
			return kStockWords[i].word;
	// Reserved words that name float functions (seed) arrive as FLOAT_FUNCT_TOKEN, the word in
	// Function_Id.
	if (token.Token_Id == FLOAT_FUNCT_TOKEN && token.Function_Id == SEED_TOKEN)
		return Word::Seed;
	if (token.End_Of_File || token.Token_Id == END_OF_FILE_TOKEN || token.Token_Id == STRING_LITERAL_TOKEN ||
	    token.Token_String == NULL)
		return Word::None;
	for (size_t i = 0; i < sizeof(kContextWords) / sizeof(kContextWords[0]); i++)
		if (std::strcmp(token.Token_String, kContextWords[i].text) == 0)
			return kContextWords[i].word;
	return Word::None;
}

std::string Check_F_Number(const char *, DBL value) { return plenoptic::check_f_number(value); }
std::string Check_Focus_Distance(const char *, DBL value) { return plenoptic::check_focus_distance(value); }
std::string Check_Mm_Per_Unit(const char *, DBL value) { return plenoptic::check_mm_per_unit(value); }
std::string Check_Confidence(const char *, DBL value) { return plenoptic::check_confidence(value); }
std::string Check_Variance(const char *, DBL value) { return plenoptic::check_variance(value); }
std::string Check_Blades(const char *, DBL value) { return plenoptic::check_blades(value); }
std::string Check_Finite_Only(const char *, DBL) { return ""; }
std::string Check_Wavelength(const char *, DBL value) { return plenoptic::check_wavelength(value); }
std::string Check_Angular_Exponent(const char *, DBL value) { return plenoptic::check_angular_exponent(value); }

// Most bytes read from a lens file: a prescription is a few hundred; this bounds a wrong file
// (a device, an image) to a prompt refusal.
const size_t kMaxLensFileBytes = 1 << 20;
// A traced lens with this many surfaces or more prints its setup's progress (about a second's work for 100).
const size_t kSetupProgressSurfaces = 100;

bool Finite(const VECTOR v) { return std::isfinite(v[X]) && std::isfinite(v[Y]) && std::isfinite(v[Z]); }

// Parse_Camera marks an unset look_at, up or right with HUGE_VAL in every component.
bool Finite_Or_Unset(const VECTOR v) { return Finite(v) || (v[X] == HUGE_VAL && v[Y] == HUGE_VAL && v[Z] == HUGE_VAL); }

}

// Raises a parse error at the current token when a check returned a message.
void Parser::Plenoptic_Check(const std::string& message)
{
	if (!message.empty())
		Error("plenoptic camera: %s.", message.c_str());
}

// An unknown keyword inside one of our blocks is an error that names it and what is allowed.
void Parser::Plenoptic_Unknown(const char *block, const char *allowed)
{
	if (Token.End_Of_File || Token.Token_Id == END_OF_FILE_TOKEN)
		Error("plenoptic camera: the file ends inside %s, before its closing '}'; allowed: %s.", block, allowed);
	const char *found = (Token.Token_String != NULL && Token.Token_String[0] != '\0') ? Token.Token_String : Get_Token_String(Token.Token_Id);
	Error("plenoptic camera: '%s' is not a %s keyword; allowed: %s.", found, block, allowed);
}

// Called by Parse_Camera once POV-Ray has resolved the placement (look_at, sky, transforms):
// the frame the camera will use must span 3-D space. The error names the last placement
// keyword, the one that completed the degenerate frame.
void Parser::Plenoptic_Check_Placement(const Camera& Cam)
{
	const std::string message = plenoptic::check_placement(Cam.Right, Cam.Up, Cam.Direction);
	if (message.empty() || !Cam.Plenoptic)
	{
		Plenoptic_Check(message);
		return;
	}
	const plenoptic::CameraSetup::KeywordSource& source = Cam.Plenoptic->last_placement;
	if (source.keyword.empty())
		Plenoptic_Check(message);
	pov_base::ITextStream::FilePos position;
	position.lineno = source.line;
	position.offset = source.offset;
	Plenoptic_Check_At(message + " (after '" + source.keyword + "')", position, (int)source.column);
}

// Before an optional value (depth_map [off], samples N [, MAX]): whether the next token is a
// keyword of the camera (or its closing brace), which is then not taken for the value even
// where the scene declared an identifier of that name.
bool Parser::Plenoptic_Keyword_Follows()
{
	Get_Token();
	const bool keyword = (Word_Of(Token) != Word::None);
	UNGET
	return keyword;
}

// A microlens array has one kind of lens: pinhole, focal_length or focal_lengths.
void Parser::Plenoptic_One_Lens_Kind(bool already_given)
{
	if (already_given)
		Error("plenoptic camera: microlens_array takes one of pinhole, focal_length or focal_lengths, not several.");
}

// Value errors point at the keyword: once its value is read, POV-Ray's current token is
// already the next one, which may sit on a later line.
void Parser::Plenoptic_Check_At(const std::string& message, const pov_base::ITextStream::FilePos& position, int column)
{
	if (message.empty())
		return;
	const std::string text = "plenoptic camera: " + message + ".";
	if (Token.FileHandle != NULL)
		messageFactory.ErrorAt(POV_EXCEPTION(kParseErr, text.c_str()), Token.FileHandle->name(), position.lineno,
		                       column, position.offset, "%s", text.c_str());
	else
		Error("%s", text.c_str());
}

// The float after the current keyword, finite and passing `check` (which may be NULL).
DBL Parser::Plenoptic_Float(const char *keyword, Plenoptic_Value_Check check)
{
	const pov_base::ITextStream::FilePos position = Token.Token_File_Pos;
	const int column = Token.Token_Col_No;
	DBL value = Parse_Float();
	Plenoptic_Check_At(plenoptic::check_finite(keyword, value), position, column);
	if (check != NULL)
		Plenoptic_Check_At(check(keyword, value), position, column);
	return value;
}

// The vector (count 2 or 3) after the current keyword, each component finite and passing `check`.
void Parser::Plenoptic_Values(const char *keyword, DBL *values, int count, Plenoptic_Value_Check check)
{
	const pov_base::ITextStream::FilePos position = Token.Token_File_Pos;
	const int column = Token.Token_Col_No;
	VECTOR v;
	UV_VECT uv;
	if (count == 2)
		Parse_UV_Vect(uv);
	else
		Parse_Vector(v);
	for (int i = 0; i < count; i++)
	{
		values[i] = (count == 2) ? uv[i] : v[i];
		Plenoptic_Check_At(plenoptic::check_finite(keyword, values[i]), position, column);
		if (check != NULL)
			Plenoptic_Check_At(check(keyword, values[i]), position, column);
	}
}

void Parser::Parse_Plenoptic_Main_Lens(plenoptic::CameraParams& params)
{
	plenoptic::MainLensParams& lens = params.main;
	lens = plenoptic::MainLensParams();
	lens.given = true;

	// Where f_number or aperture was written: a real lens that cannot deliver it is refused there.
	pov_base::ITextStream::FilePos stop_position = Token.Token_File_Pos;
	int stop_column = -1;
	Parse_Begin();
	for (Get_Token(); Word_Of(Token) != Word::CloseBlock; Get_Token())
	{
		if (Word_Of(Token) == Word::FNumber || Word_Of(Token) == Word::Aperture)
		{
			stop_position = Token.Token_File_Pos;
			stop_column = Token.Token_Col_No;
		}
		switch (Word_Of(Token))
		{
			case Word::ThinLens:
			case Word::Pinhole:
			case Word::ThickLens:
				if (lens.type != plenoptic::MainLensType::None)
					Error("plenoptic camera: main_lens takes one of thin_lens, pinhole or thick_lens, not several.");
				lens.type = (Word_Of(Token) == Word::ThinLens) ? plenoptic::MainLensType::ThinLens :
				            (Word_Of(Token) == Word::Pinhole) ? plenoptic::MainLensType::Pinhole : plenoptic::MainLensType::ThickLens;
				break;
			case Word::LensFile:
			case Word::Prescription:
				if (lens.has_prescription)
					Error("plenoptic camera: main_lens takes one lens_file or one prescription { }, not several.");
				if (Word_Of(Token) == Word::LensFile)
					Parse_Plenoptic_Lens_File(lens);
				else
					Parse_Plenoptic_Prescription(lens);
				lens.has_prescription = true;
				break;
			case Word::Blades:
				lens.blades = (int)Plenoptic_Float("blades", Check_Blades);
				break;
			case Word::BladeRotation:
				lens.blade_rotation_deg = Plenoptic_Float("blade_rotation", plenoptic::check_angle);
				break;
			case Word::FocalLength:
				lens.focal_length_mm = Plenoptic_Float("main_lens focal_length", plenoptic::check_positive_length);
				lens.has_focal_length = true;
				break;
			case Word::FNumber:
				lens.f_number = Plenoptic_Float("f_number", Check_F_Number);
				lens.has_f_number = true;
				break;
			case Word::Aperture:
				lens.aperture_mm = Plenoptic_Float("aperture", plenoptic::check_positive_length);
				lens.has_aperture = true;
				break;
			case Word::FocusDistance:
				lens.focus_distance_units = Plenoptic_Float("focus_distance", Check_Focus_Distance);
				lens.has_focus_distance = true;
				break;
			case Word::Distance:
				lens.distance_mm = Plenoptic_Float("main_lens distance", plenoptic::check_positive_length);
				lens.has_distance = true;
				break;
			case Word::Distortion:
				// distortion { radial <k1, k2, k3> tangential <p1, p2> } (lens/distortion.h); either may be left out.
				if (lens.has_distortion)
					Error("plenoptic camera: main_lens takes one distortion { }, not several.");
				lens.has_distortion = true;
				Parse_Begin();
				for (Get_Token(); Word_Of(Token) != Word::CloseBlock; Get_Token())
				{
					if (Word_Of(Token) == Word::Radial)
						Plenoptic_Values("distortion radial", lens.distortion.radial, 3, NULL);
					else if (Word_Of(Token) == Word::Tangential)
						Plenoptic_Values("distortion tangential", lens.distortion.tangential, 2, NULL);
					else
						Plenoptic_Unknown("distortion", kDistortionKeywords);
				}
				UNGET
				Parse_End();
				break;
			default:
				Plenoptic_Unknown("main_lens", kMainLensKeywords);
		}
	}
	// The iris turned by a multiple of 360 / blades is the same iris: the metadata keeps the turn in [0, 360 / blades).
	lens.blade_rotation_deg = plenoptic::reduced_blade_rotation(lens.blade_rotation_deg, lens.blades);
	// A real lens without thin_lens, pinhole or thick_lens is traced surface by surface.
	if (lens.type == plenoptic::MainLensType::None && lens.has_prescription)
		lens.type = plenoptic::MainLensType::Prescription;
	// The closing brace is current: cross-field errors point at the end of the block; a stop the
	// lens cannot deliver, at its f_number or aperture.
	const std::string lens_message = plenoptic::check_main_lens(lens, params.mm_per_unit);
	if (!lens_message.empty() && stop_column >= 0 && lens_message == plenoptic::check_aperture_reach(lens, params.mm_per_unit))
		Plenoptic_Check_At(lens_message, stop_position, stop_column);
	Plenoptic_Check(lens_message);
	UNGET
	Parse_End();
}

// lens_file "name": pbrt's lens-file format (lens/prescription.h), found as POV-Ray finds a
// file the scene reads (beside the scene, then the library paths), and else in the lenses/
// folder installed with the program. Errors name the file and its row.
void Parser::Parse_Plenoptic_Lens_File(plenoptic::MainLensParams& lens)
{
	const pov_base::ITextStream::FilePos position = Token.Token_File_Pos;
	const int column = Token.Token_Col_No;
	char *name = Parse_C_String(true);
	const std::string file(name);
	POV_FREE(name);
	if (file.empty())
		Plenoptic_Check_At("lens_file \"\" names no file: give the name of a lens file (pbrt's format, one row per surface)",
		                   position, column);
	UCS2String found;
	IStream *stream = Locate_File(this, sceneData, ASCIItoUCS2String(file.c_str()), POV_File_Text_User, found, false);
	if (stream == NULL)
		stream = Locate_File(this, sceneData, ASCIItoUCS2String(("lenses/" + file).c_str()), POV_File_Text_User, found, false);
	if (stream == NULL)
		Plenoptic_Check_At("lens_file \"" + file + "\" was not found beside the scene, in the library paths (+L) or in "
		                   "the lenses folder installed with the program", position, column);
	// A directory opens, and reads as no bytes: say what it is rather than "no surface".
	struct stat status;
	const std::string path = UCS2toASCIIString(found);
	if (stat(path.c_str(), &status) == 0 && S_ISDIR(status.st_mode))
	{
		delete stream;
		Plenoptic_Check_At("lens_file \"" + file + "\" names a directory (" + path + "), not a lens file", position, column);
	}
	std::string text;
	for (int c = stream->Read_Byte(); c != EOF && text.size() <= kMaxLensFileBytes; c = stream->Read_Byte())
		text.push_back((char)c);
	delete stream;
	if (text.size() > kMaxLensFileBytes)
		Plenoptic_Check_At("lens_file \"" + file + "\" is larger than " + std::to_string(kMaxLensFileBytes) +
		                   " bytes: not a lens file", position, column);
	const plenoptic::ParsedPrescription parsed = plenoptic::parse_lens_file(text);
	if (parsed.error.any())
		Plenoptic_Check_At("lens_file \"" + file + "\"" + (parsed.error.line > 0 ? ", line " + std::to_string(parsed.error.line) : std::string()) +
		                   ": " + parsed.error.message, position, column);
	lens.prescription.surfaces = parsed.prescription.surfaces;
	lens.lens_file = file;
}

// prescription { surface { radius R thickness t ior n aperture a } stop { thickness t aperture a } ... }:
// the rows of a lens file, object side first, written in the scene. Every value is required.
void Parser::Parse_Plenoptic_Prescription(plenoptic::MainLensParams& lens)
{
	lens.prescription.surfaces.clear();
	Parse_Begin();
	for (Get_Token(); Word_Of(Token) != Word::CloseBlock; Get_Token())
	{
		const Word row = Word_Of(Token);
		if (row != Word::Surface && row != Word::Stop)
			Plenoptic_Unknown("prescription", kPrescriptionKeywords);
		// A stop keeps the medium it stands in (index 0, as in a lens file); a radius 0 surface is flat.
		plenoptic::LensSurface surface = {0, 0, row == Word::Stop ? 0.0 : 1.0, 0, row == Word::Stop, (int)Token.Token_File_Pos.lineno};
		const char *block = surface.stop ? "stop" : "surface";
		bool has_radius = surface.stop, has_thickness = false, has_ior = surface.stop, has_aperture = false;
		Parse_Begin();
		for (Get_Token(); Word_Of(Token) != Word::CloseBlock; Get_Token())
		{
			const Word word = Word_Of(Token);
			if (word == Word::Radius && !surface.stop)
			{
				// Beyond +-1e12 mm (the bound of every length) a radius is flat, as in a lens file.
				surface.radius_mm = plenoptic::flat_radius(Plenoptic_Float("surface radius", Check_Finite_Only));
				has_radius = true;
			}
			else if (word == Word::Thickness)
			{
				surface.thickness_mm = Plenoptic_Float(surface.stop ? "stop thickness" : "surface thickness", plenoptic::check_translation);
				has_thickness = true;
			}
			else if (word == Word::Ior && !surface.stop)
			{
				surface.ior = Plenoptic_Float("surface ior", Check_Finite_Only);
				has_ior = true;
			}
			else if (word == Word::Aperture)
			{
				surface.aperture_mm = Plenoptic_Float(surface.stop ? "stop aperture" : "surface aperture", plenoptic::check_positive_length);
				has_aperture = true;
			}
			else
				Plenoptic_Unknown(block, surface.stop ? kStopKeywords : kSurfaceKeywords);
		}
		if (!(has_radius && has_thickness && has_ior && has_aperture))
			Error("plenoptic camera: %s needs %s.", block, surface.stop ? "thickness and aperture" : "radius, thickness, ior and aperture");
		UNGET
		Parse_End();
		lens.prescription.surfaces.push_back(surface);
	}
	const plenoptic::PrescriptionError error = plenoptic::check_prescription(lens.prescription);
	if (error.any())
	{
		pov_base::ITextStream::FilePos position = Token.Token_File_Pos;
		position.lineno = error.line > 0 ? error.line : position.lineno;
		Plenoptic_Check_At("prescription: " + error.message, position, error.line > 0 ? 1 : (int)Token.Token_Col_No);
	}
	UNGET
	Parse_End();
	lens.lens_file.clear();
}

void Parser::Parse_Plenoptic_Array(plenoptic::CameraParams& params)
{
	plenoptic::ArrayParams& array = params.array;
	array = plenoptic::ArrayParams();
	array.given = true;
	bool had_rotate = false, had_translate = false;

	Parse_Begin();
	for (Get_Token(); Word_Of(Token) != Word::CloseBlock; Get_Token())
	{
		switch (Word_Of(Token))
		{
			case Word::Hexagonal:
			case Word::Rectangular:
				if (array.grid != plenoptic::GridType::None)
					Error("plenoptic camera: microlens_array takes one of hexagonal or rectangular, not both.");
				array.grid = (Word_Of(Token) == Word::Hexagonal) ? plenoptic::GridType::Hexagonal : plenoptic::GridType::Rectangular;
				break;
			case Word::Pitch:
				array.pitch_mm = Plenoptic_Float("pitch", plenoptic::check_positive_length);
				array.has_pitch = true;
				break;
			case Word::FocalLength:
				Plenoptic_One_Lens_Kind(array.has_lens);
				array.focal_lengths_mm[0] = Plenoptic_Float("microlens_array focal_length", plenoptic::check_positive_length);
				array.focal_length_count = 1;
				array.lens = plenoptic::MicrolensType::ThinLens;
				array.has_lens = true;
				break;
			case Word::FocalLengths:
				Plenoptic_One_Lens_Kind(array.has_lens);
				Plenoptic_Values("focal_lengths", array.focal_lengths_mm, 3, plenoptic::check_positive_length);
				array.focal_length_count = 3;
				array.lens = plenoptic::MicrolensType::ThinLens;
				array.has_lens = true;
				break;
			case Word::Pinhole:
				Plenoptic_One_Lens_Kind(array.has_lens);
				array.focal_length_count = 0;
				array.lens = plenoptic::MicrolensType::Pinhole;
				array.has_lens = true;
				break;
			case Word::Distance:
				array.distance_mm = Plenoptic_Float("microlens_array distance", plenoptic::check_positive_length);
				array.has_distance = true;
				break;
			case Word::Rotate:
				// The pose is one rotation then one translation (docs/specification.md, section 2): not a chain.
				if (had_rotate)
					Error("plenoptic camera: microlens_array takes rotate once (about x, then y, then z, in degrees).");
				had_rotate = true;
				Plenoptic_Values("microlens_array rotate", array.rotate_deg, 3, plenoptic::check_angle);
				break;
			case Word::Translate:
				if (had_translate)
					Error("plenoptic camera: microlens_array takes translate once (mm, after the rotation).");
				had_translate = true;
				Plenoptic_Values("microlens_array translate", array.translate_mm, 3, plenoptic::check_translation);
				break;
			default:
				Plenoptic_Unknown("microlens_array", kArrayKeywords);
		}
	}
	Plenoptic_Check(plenoptic::check_array(array));
	UNGET
	Parse_End();
}

void Parser::Parse_Plenoptic_Sensor(plenoptic::CameraParams& params)
{
	// A second sensor { } replaces the first entirely, as the other blocks do.
	plenoptic::SensorParams& sensor = params.sensor;
	sensor = plenoptic::SensorParams();
	plenoptic::SensorChainParams& chain = sensor.chain;

	Parse_Begin();
	for (Get_Token(); Word_Of(Token) != Word::CloseBlock; Get_Token())
	{
		switch (Word_Of(Token))
		{
			case Word::PixelSize:
				Plenoptic_Values("pixel_size", sensor.pixel_size_mm, 2, plenoptic::check_positive_length);
				break;
			case Word::Offset:
				Plenoptic_Values("sensor offset", sensor.offset_mm, 2, plenoptic::check_translation);
				break;
			case Word::AngularResponse:
				sensor.angular_exponent = Plenoptic_Float("angular_response", Check_Angular_Exponent);
				break;
			case Word::Bayer:
			{
				// The pattern is a word of its own, read by its text as the camera's keywords are.
				Get_Token();
				const char *text = (Token.Token_Id != STRING_LITERAL_TOKEN && !Token.End_Of_File) ? Token.Token_String : NULL;
				const plenoptic::BayerPattern patterns[] = {plenoptic::BayerPattern::RGGB, plenoptic::BayerPattern::BGGR,
				                                            plenoptic::BayerPattern::GRBG, plenoptic::BayerPattern::GBRG};
				bool known = false;
				for (size_t i = 0; i < sizeof(patterns) / sizeof(patterns[0]) && text != NULL; i++)
					if (std::strcmp(text, plenoptic::bayer_name(patterns[i])) == 0)
					{
						chain.bayer = patterns[i];
						known = true;
					}
				if (!known)
					Error("plenoptic camera: bayer takes one of %s, not '%s'.", kBayerPatterns,
					      text != NULL ? text : Get_Token_String(Token.Token_Id));
				chain.given = true;
				break;
			}
			case Word::BitDepth:
				chain.bit_depth = (int)Plenoptic_Float("bit_depth", plenoptic::check_bit_depth);
				chain.given = true;
				break;
			case Word::FullWell:
				chain.full_well_e = Plenoptic_Float("full_well", plenoptic::check_electrons);
				chain.given = true;
				break;
			case Word::Exposure:
				chain.exposure_e = Plenoptic_Float("exposure", plenoptic::check_electrons);
				chain.has_exposure = true;
				chain.given = true;
				break;
			case Word::ReadNoise:
				chain.read_noise_e = Plenoptic_Float("read_noise", plenoptic::check_non_negative);
				chain.given = true;
				break;
			case Word::DarkCurrent:
				chain.dark_current_e_per_s = Plenoptic_Float("dark_current", plenoptic::check_non_negative);
				chain.given = true;
				break;
			case Word::ExposureTime:
				chain.exposure_time_s = Plenoptic_Float("exposure_time", plenoptic::check_non_negative);
				chain.given = true;
				break;
			case Word::Prnu:
				chain.prnu = Plenoptic_Float("prnu", plenoptic::check_non_negative);
				chain.given = true;
				break;
			case Word::Dsnu:
				chain.dsnu_e = Plenoptic_Float("dsnu", plenoptic::check_non_negative);
				chain.given = true;
				break;
			case Word::BlackLevel:
				chain.black_level_dn = (int)Plenoptic_Float("black_level", plenoptic::check_dn);
				chain.given = true;
				break;
			case Word::Seed:
				chain.seed = (std::uint64_t)Plenoptic_Float("seed", plenoptic::check_whole_number);
				chain.given = true;
				break;
			default:
				Plenoptic_Unknown("sensor", kSensorKeywords);
		}
	}
	Plenoptic_Check(plenoptic::check_sensor(sensor));
	UNGET
	Parse_End();
}

// samples N            a fixed count
// samples MIN, MAX     adaptive, stopping on confidence/variance as focal_blur does
void Parser::Parse_Plenoptic_Samples(plenoptic::CameraParams& params)
{
	plenoptic::SamplingParams& sampling = params.sampling;
	const pov_base::ITextStream::FilePos position = Token.Token_File_Pos;
	const int column = Token.Token_Col_No;
	DBL first = Plenoptic_Float("samples", plenoptic::check_samples);
	Parse_Comma();
	DBL second = Plenoptic_Keyword_Follows() ? 0.0 : Allow_Float(0.0);
	if (second == 0.0)
	{
		sampling.adaptive = false;
		sampling.samples = (int)first;
		return;
	}
	Plenoptic_Check_At(plenoptic::check_adaptive_minimum(first), position, column);
	Plenoptic_Check_At(plenoptic::check_finite("samples maximum", second), position, column);
	Plenoptic_Check_At(plenoptic::check_samples("samples maximum", second), position, column);
	if (first > second)
		Plenoptic_Check_At("samples minimum (" + plenoptic::format_number(first) + ") must not be larger than the maximum (" +
		                   plenoptic::format_number(second) + ")", position, column);
	sampling.adaptive = true;
	sampling.samples_min = (int)first;
	sampling.samples_max = (int)second;
	sampling.samples = (int)second;
}

void Parser::Parse_Plenoptic_Camera(Camera& New)
{
	POV_TR1_NAMESPACE::shared_ptr<plenoptic::CameraSetup> setup(new plenoptic::CameraSetup());
	plenoptic::CameraParams& params = setup->params;
	// A camera declared earlier and modified here keeps its plenoptic parameters.
	if (New.Plenoptic)
	{
		params = New.Plenoptic->params;
		setup->depth_map = New.Plenoptic->depth_map;
		setup->microimage_centres = New.Plenoptic->microimage_centres;
		setup->white_image = New.Plenoptic->white_image;
	}

	for (Get_Token(); Word_Of(Token) != Word::CloseBlock; Get_Token())
	{
		switch (Word_Of(Token))
		{
			case Word::MmPerUnit:
				params.mm_per_unit = Plenoptic_Float("mm_per_unit", Check_Mm_Per_Unit);
				continue;
			case Word::MainLens:
				Parse_Plenoptic_Main_Lens(params);
				continue;
			case Word::MicrolensArray:
				Parse_Plenoptic_Array(params);
				continue;
			case Word::Sensor:
				Parse_Plenoptic_Sensor(params);
				continue;
			case Word::Samples:
				Parse_Plenoptic_Samples(params);
				continue;
			case Word::Confidence:
				params.sampling.confidence = Plenoptic_Float("confidence", Check_Confidence);
				continue;
			case Word::Variance:
				params.sampling.variance = Plenoptic_Float("variance", Check_Variance);
				continue;
			case Word::DepthMap:
				setup->depth_map = Plenoptic_Keyword_Follows() || ((int)Allow_Float(1.0) != 0);
				continue;
			case Word::MicroimageCentres:
				setup->microimage_centres = (Plenoptic_Keyword_Follows() || ((int)Allow_Float(1.0) != 0))
					? plenoptic::CameraSetup::kWrite : plenoptic::CameraSetup::kDoNotWrite;
				continue;
			case Word::Radiometry:
			{
				// radiometry flat | irradiance: the word read by its text, as bayer's pattern.
				Get_Token();
				const char *text = (Token.Token_Id != STRING_LITERAL_TOKEN && !Token.End_Of_File) ? Token.Token_String : NULL;
				const plenoptic::Radiometry kinds[] = {plenoptic::Radiometry::Flat, plenoptic::Radiometry::Irradiance};
				bool known = false;
				for (size_t i = 0; i < sizeof(kinds) / sizeof(kinds[0]) && text != NULL; i++)
					if (std::strcmp(text, plenoptic::radiometry_name(kinds[i])) == 0)
					{
						params.radiometry = kinds[i];
						known = true;
					}
				if (!known)
					Error("plenoptic camera: radiometry takes one of %s, not '%s'.", kRadiometries,
					      text != NULL ? text : Get_Token_String(Token.Token_Id));
				continue;
			}
			case Word::Diffraction:
				// diffraction [on | off] [wavelengths <r, g, b>] (nm)
				params.diffraction = plenoptic::DiffractionParams();
				params.diffraction.given = Plenoptic_Keyword_Follows() || ((int)Allow_Float(1.0) != 0);
				Get_Token();
				if (Word_Of(Token) == Word::Wavelengths)
					Plenoptic_Values("diffraction wavelengths", params.diffraction.wavelengths_nm, 3, Check_Wavelength);
				else
					UNGET
				continue;
			case Word::WhiteImage:
			{
				// white_image [on | off] [f_numbers N | f_numbers <N1, ..., N16>] [noise_free]
				plenoptic::WhiteImageRequest& white = setup->white_image;
				white = plenoptic::WhiteImageRequest();
				setup->white_f_numbers = plenoptic::CameraSetup::KeywordSource();
				white.given = Plenoptic_Keyword_Follows() || ((int)Allow_Float(1.0) != 0);
				for (;;)
				{
					Get_Token();
					if (Word_Of(Token) == Word::FNumbers)
					{
						const pov_base::ITextStream::FilePos position = Token.Token_File_Pos;
						const int column = Token.Token_Col_No;
						// One f-number, or a list in angle brackets as a vector's components are read.
						std::vector<DBL> values;
						Get_Token();
						if (Token.Token_Id == LEFT_ANGLE_TOKEN)
						{
							for (;;)
							{
								values.push_back(Parse_Float());
								Parse_Comma();
								Get_Token();
								if (Token.Token_Id == RIGHT_ANGLE_TOKEN)
									break;
								UNGET
								if ((int)values.size() >= plenoptic::kMaxWhiteImages)
									Plenoptic_Check_At("white_image f_numbers lists at most " +
									                   plenoptic::format_number(plenoptic::kMaxWhiteImages) +
									                   " f-numbers, between '<' and '>'", position, column);
							}
						}
						else
						{
							UNGET
							values.push_back(Parse_Float());
						}
						white.f_numbers.clear();
						for (size_t k = 0; k < values.size(); k++)
						{
							Plenoptic_Check_At(plenoptic::check_finite("white_image f_numbers", values[k]), position, column);
							Plenoptic_Check_At(plenoptic::check_f_number(values[k]).empty() ? "" :
							                   "white_image f_numbers: " + plenoptic::check_f_number(values[k]), position, column);
							white.f_numbers.push_back(values[k]);
						}
						// A value listed twice is refused here; one the camera cannot take is found at the
						// camera's brace, and reported here too.
						Plenoptic_Check_At(plenoptic::repeated_white_f_number(white), position, column);
						setup->white_f_numbers.keyword = "f_numbers";
						setup->white_f_numbers.line = position.lineno;
						setup->white_f_numbers.column = column;
						setup->white_f_numbers.offset = position.offset;
					}
					else if (Word_Of(Token) == Word::NoiseFree)
						white.noise_free = true;
					else
					{
						UNGET
						break;
					}
				}
				continue;
			}
			case Word::Aperture:
				break;  // refused below with focal blur's other words
			case Word::None:
			case Word::Rotate:
			case Word::Translate:
				break;  // stock camera modifiers, below
			default:
				// A word of one of the blocks, out of its block.
				Plenoptic_Unknown("plenoptic camera", kPlenopticKeywords);
		}

		switch (Token.Token_Id)
		{
			// Focal blur and field-of-view modifiers would silently mean nothing here.
			CASE5 (APERTURE_TOKEN, BLUR_SAMPLES_TOKEN, FOCAL_POINT_TOKEN, BOKEH_TOKEN, ANGLE_TOKEN)
				Error("plenoptic camera: '%s' does not apply to a plenoptic camera (the aperture, focus and field "
				      "of view come from main_lens { }, microlens_array { } and sensor { }).",
				      Get_Token_String(Token.Token_Id));
			END_CASE

			CASE (TNORMAL_TOKEN)
				Error("plenoptic camera: 'normal' (ray perturbation) is not supported by the plenoptic camera.");
			END_CASE

			CASE6 (PERSPECTIVE_TOKEN, ORTHOGRAPHIC_TOKEN, FISHEYE_TOKEN, ULTRA_WIDE_ANGLE_TOKEN, OMNIMAX_TOKEN, PANORAMIC_TOKEN)
			CASE3 (SPHERICAL_TOKEN, CYLINDER_TOKEN, MESH_CAMERA_TOKEN)
				Expectation_Error("plenoptic camera modifier");
			END_CASE

			default:
			{
				const pov_base::ITextStream::FilePos position = Token.Token_File_Pos;
				const int column = Token.Token_Col_No;
				const TOKEN keyword = Token.Token_Id;
				UNGET
				if (Parse_Camera_Mods(New) == false)
				{
					Get_Token();
					Plenoptic_Unknown("plenoptic camera", kPlenopticKeywords);
				}
				// Placement too must be finite (POV-Ray's stock cameras would render black).
				bool finite = Finite(New.Location) && Finite(New.Sky) && Finite(New.Direction) &&
				              Finite_Or_Unset(New.Look_At) && Finite_Or_Unset(New.Up) && Finite_Or_Unset(New.Right);
				for (int r = 0; r < 4 && New.Trans != NULL; r++)
					for (int c = 0; c < 4; c++)
						finite = finite && std::isfinite(New.Trans->matrix[r][c]) && std::isfinite(New.Trans->inverse[r][c]);
				if (!finite)
					Plenoptic_Check_At(std::string("'") + Get_Token_String(keyword) + "' gives a value that is not a finite "
					                   "number (NaN or infinite)", position, column);
				// A zero right, up or direction leaves the camera without a frame.
				const DBL *given = (keyword == RIGHT_TOKEN) ? New.Right : (keyword == UP_TOKEN) ? New.Up :
				                   (keyword == DIRECTION_TOKEN) ? New.Direction : (keyword == SKY_TOKEN) ? New.Sky : NULL;
				if (given != NULL && !(given[X] * given[X] + given[Y] * given[Y] + given[Z] * given[Z] > 0))
					Plenoptic_Check_At(std::string("'") + Get_Token_String(keyword) + "' is a zero vector: the camera's "
					                   "right, up, direction and sky must have a non-zero length", position, column);
				setup->last_placement.keyword = Get_Token_String(keyword);
				setup->last_placement.line = position.lineno;
				setup->last_placement.column = column;
				setup->last_placement.offset = position.offset;
			}
		}
	}

	// The camera's closing brace is current for the checks across blocks.
	Plenoptic_Check(plenoptic::check_camera(params));
	if (setup->white_image.given)
	{
		// An f-number the camera cannot take is refused at the f_numbers keyword; the rest here.
		const std::string white = plenoptic::check_white_image(setup->white_image, params);
		if (!white.empty() && !setup->white_f_numbers.keyword.empty() &&
		    white == plenoptic::check_white_image_f_numbers(setup->white_image, params))
		{
			pov_base::ITextStream::FilePos position;
			position.lineno = setup->white_f_numbers.line;
			position.offset = setup->white_f_numbers.offset;
			Plenoptic_Check_At(white, position, (int)setup->white_f_numbers.column);
		}
		Plenoptic_Check(white);
	}
	Plenoptic_Check(plenoptic::check_diffraction(params.diffraction, params));
	{
		// A traced lens's tables cost a fixed number of traces, each linear in its surfaces: a lens of
		// 2,000 surfaces sets up for tens of seconds. Ctrl-C stops the parse there as anywhere (the
		// parser's Cooperate throws), and a lens of many surfaces says how far on stderr.
		const size_t surfaces = params.main.prescription.surfaces.size();
		std::string last_step;
		int last_tenth = -1;
		plenoptic::ScopedSetupReporter reporter([&](const char *step, int done, int total)
		{
			Cooperate();
			if (surfaces < kSetupProgressSurfaces)
				return;
			const int tenth = total > 0 ? std::min(10, done * 10 / total) : 10;
			if (tenth == last_tenth && last_step == step)
				return;
			last_tenth = tenth;
			last_step = step;
			std::fprintf(stderr, "plenoptic camera: setting up a lens of %zu surfaces: %s %d %%\n", surfaces, step, 10 * tenth);
		});
		setup->model = plenoptic::make_model(params);
		Plenoptic_Check(plenoptic::check_diffraction_size(setup->model, params.diffraction));
		for (size_t k = 0; k < setup->white_image.f_numbers.size() && params.diffraction.given; k++)
			Plenoptic_Check(plenoptic::check_diffraction_size(
				plenoptic::make_model(plenoptic::at_f_number(params, setup->white_image.f_numbers[k])), params.diffraction));
	}
	UNGET
	std::vector<std::string> warnings = plenoptic::warnings(setup->model);
	const std::string dark = plenoptic::dark_image_warning(setup->model);
	if (!dark.empty())
		warnings.push_back(dark);
	for (size_t i = 0; i < warnings.size(); i++)
		Warning(0, "plenoptic camera: %s", warnings[i].c_str());
	New.Plenoptic = setup;
}

}
