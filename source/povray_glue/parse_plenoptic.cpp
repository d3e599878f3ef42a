// SPDX-License-Identifier: AGPL-3.0-or-later
// Parser for the body of `camera { plenoptic ... }`. Every value is checked while its
// token is current, so POV-Ray's error names the file and line; cross-field checks run
// when a block's closing brace is read. The optics themselves live in source/plenoptic/.

#include <cmath>
#include <string>

#include "backend/frame.h"
#include "backend/parser/parse.h"
#include "backend/scene/camera.h"
#include "povray_glue/plenoptic_setup.h"

#include "base/povdebug.h"

namespace pov
{

namespace
{

const char *kPlenopticKeywords =
	"main_lens { }, microlens_array { }, sensor { }, mm_per_unit, samples, confidence, variance, depth_map, "
	"and the placement keywords of every camera (location, look_at, sky, right, up, direction, rotate, "
	"translate, scale, matrix, transform)";
const char *kMainLensKeywords = "thin_lens, pinhole, focal_length, f_number, aperture, focus_distance, distance";
const char *kArrayKeywords = "hexagonal, rectangular, pitch, focal_length, focal_lengths, pinhole, distance, rotate, translate";
const char *kSensorKeywords = "pixel_size, offset";

std::string Check_F_Number(const char *, DBL value) { return plenoptic::check_f_number(value); }
std::string Check_Focus_Distance(const char *, DBL value) { return plenoptic::check_focus_distance(value); }
std::string Check_Mm_Per_Unit(const char *, DBL value) { return plenoptic::check_mm_per_unit(value); }
std::string Check_Confidence(const char *, DBL value) { return plenoptic::check_confidence(value); }
std::string Check_Variance(const char *, DBL value) { return plenoptic::check_variance(value); }

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
	const char *found = (Token.Token_String != NULL && Token.Token_String[0] != '\0') ? Token.Token_String : Get_Token_String(Token.Token_Id);
	Error("plenoptic camera: '%s' is not a %s keyword; allowed: %s.", found, block, allowed);
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

	Parse_Begin();
	EXPECT
		CASE2 (THIN_LENS_TOKEN, PINHOLE_TOKEN)
			if (lens.type != plenoptic::MainLensType::None)
				Error("plenoptic camera: main_lens takes one of thin_lens or pinhole, not both.");
			lens.type = (Token.Token_Id == THIN_LENS_TOKEN) ? plenoptic::MainLensType::ThinLens : plenoptic::MainLensType::Pinhole;
		END_CASE

		CASE (FOCAL_LENGTH_TOKEN)
			lens.focal_length_mm = Plenoptic_Float("main_lens focal_length", plenoptic::check_positive_length);
			lens.has_focal_length = true;
		END_CASE

		CASE (F_NUMBER_TOKEN)
			lens.f_number = Plenoptic_Float("f_number", Check_F_Number);
			lens.has_f_number = true;
		END_CASE

		CASE (APERTURE_TOKEN)
			lens.aperture_mm = Plenoptic_Float("aperture", plenoptic::check_positive_length);
			lens.has_aperture = true;
		END_CASE

		CASE (FOCUS_DISTANCE_TOKEN)
			lens.focus_distance_units = Plenoptic_Float("focus_distance", Check_Focus_Distance);
			lens.has_focus_distance = true;
		END_CASE

		CASE (DISTANCE_TOKEN)
			lens.distance_mm = Plenoptic_Float("main_lens distance", plenoptic::check_positive_length);
			lens.has_distance = true;
		END_CASE

		CASE (RIGHT_CURLY_TOKEN)
			UNGET
			EXIT
		END_CASE

		OTHERWISE
			Plenoptic_Unknown("main_lens", kMainLensKeywords);
		END_CASE
	END_EXPECT
	// The closing brace is current: cross-field errors point at the end of the block.
	Get_Token();
	Plenoptic_Check(plenoptic::check_main_lens(lens, params.mm_per_unit));
	UNGET
	Parse_End();
}

void Parser::Parse_Plenoptic_Array(plenoptic::CameraParams& params)
{
	plenoptic::ArrayParams& array = params.array;
	array = plenoptic::ArrayParams();
	array.given = true;
	bool had_rotate = false, had_translate = false;

	Parse_Begin();
	EXPECT
		CASE2 (HEXAGONAL_TOKEN, RECTANGULAR_TOKEN)
			if (array.grid != plenoptic::GridType::None)
				Error("plenoptic camera: microlens_array takes one of hexagonal or rectangular, not both.");
			array.grid = (Token.Token_Id == HEXAGONAL_TOKEN) ? plenoptic::GridType::Hexagonal : plenoptic::GridType::Rectangular;
		END_CASE

		CASE (PITCH_TOKEN)
			array.pitch_mm = Plenoptic_Float("pitch", plenoptic::check_positive_length);
			array.has_pitch = true;
		END_CASE

		CASE (FOCAL_LENGTH_TOKEN)
			Plenoptic_One_Lens_Kind(array.has_lens);
			array.focal_lengths_mm[0] = Plenoptic_Float("microlens_array focal_length", plenoptic::check_positive_length);
			array.focal_length_count = 1;
			array.lens = plenoptic::MicrolensType::ThinLens;
			array.has_lens = true;
		END_CASE

		CASE (FOCAL_LENGTHS_TOKEN)
			Plenoptic_One_Lens_Kind(array.has_lens);
			Plenoptic_Values("focal_lengths", array.focal_lengths_mm, 3, plenoptic::check_positive_length);
			array.focal_length_count = 3;
			array.lens = plenoptic::MicrolensType::ThinLens;
			array.has_lens = true;
		END_CASE

		CASE (PINHOLE_TOKEN)
			Plenoptic_One_Lens_Kind(array.has_lens);
			array.focal_length_count = 0;
			array.lens = plenoptic::MicrolensType::Pinhole;
			array.has_lens = true;
		END_CASE

		CASE (DISTANCE_TOKEN)
			array.distance_mm = Plenoptic_Float("microlens_array distance", plenoptic::check_positive_length);
			array.has_distance = true;
		END_CASE

		CASE (ROTATE_TOKEN)
			// The pose is one rotation then one translation (contract, section 2): not a chain.
			if (had_rotate)
				Error("plenoptic camera: microlens_array takes rotate once (about x, then y, then z, in degrees).");
			had_rotate = true;
			Plenoptic_Values("microlens_array rotate", array.rotate_deg, 3, plenoptic::check_angle);
		END_CASE

		CASE (TRANSLATE_TOKEN)
			if (had_translate)
				Error("plenoptic camera: microlens_array takes translate once (mm, after the rotation).");
			had_translate = true;
			Plenoptic_Values("microlens_array translate", array.translate_mm, 3, plenoptic::check_translation);
		END_CASE

		CASE (RIGHT_CURLY_TOKEN)
			UNGET
			EXIT
		END_CASE

		OTHERWISE
			Plenoptic_Unknown("microlens_array", kArrayKeywords);
		END_CASE
	END_EXPECT
	Get_Token();
	Plenoptic_Check(plenoptic::check_array(array));
	UNGET
	Parse_End();
}

void Parser::Parse_Plenoptic_Sensor(plenoptic::CameraParams& params)
{
	plenoptic::SensorParams& sensor = params.sensor;

	Parse_Begin();
	EXPECT
		CASE (PIXEL_SIZE_TOKEN)
			Plenoptic_Values("pixel_size", sensor.pixel_size_mm, 2, plenoptic::check_positive_length);
		END_CASE

		CASE (OFFSET_TOKEN)
			Plenoptic_Values("sensor offset", sensor.offset_mm, 2, plenoptic::check_translation);
		END_CASE

		CASE (RIGHT_CURLY_TOKEN)
			UNGET
			EXIT
		END_CASE

		OTHERWISE
			Plenoptic_Unknown("sensor", kSensorKeywords);
		END_CASE
	END_EXPECT
	Get_Token();
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
	DBL second = Allow_Float(0.0);
	if (second == 0.0)
	{
		sampling.adaptive = false;
		sampling.samples = (int)first;
		return;
	}
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
	}

	EXPECT
		CASE (MM_PER_UNIT_TOKEN)
			params.mm_per_unit = Plenoptic_Float("mm_per_unit", Check_Mm_Per_Unit);
		END_CASE

		CASE (MAIN_LENS_TOKEN)
			Parse_Plenoptic_Main_Lens(params);
		END_CASE

		CASE (MICROLENS_ARRAY_TOKEN)
			Parse_Plenoptic_Array(params);
		END_CASE

		CASE (SENSOR_TOKEN)
			Parse_Plenoptic_Sensor(params);
		END_CASE

		CASE (SAMPLES_TOKEN)
			Parse_Plenoptic_Samples(params);
		END_CASE

		CASE (CONFIDENCE_TOKEN)
			params.sampling.confidence = Plenoptic_Float("confidence", Check_Confidence);
		END_CASE

		CASE (VARIANCE_TOKEN)
			params.sampling.variance = Plenoptic_Float("variance", Check_Variance);
		END_CASE

		CASE (DEPTH_MAP_TOKEN)
			setup->depth_map = ((int)Allow_Float(1.0) != 0);
		END_CASE

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

		CASE (RIGHT_CURLY_TOKEN)
			UNGET
			EXIT
		END_CASE

		OTHERWISE
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
		}
		END_CASE
	END_EXPECT

	// The camera's closing brace is current for the checks across blocks.
	Get_Token();
	Plenoptic_Check(plenoptic::check_camera(params));
	UNGET
	setup->model = plenoptic::make_model(params);
	std::vector<std::string> warnings = plenoptic::warnings(setup->model);
	for (size_t i = 0; i < warnings.size(); i++)
		Warning(0, "plenoptic camera: %s", warnings[i].c_str());
	New.Plenoptic = setup;
}

}
