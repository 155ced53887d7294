#pragma once
// Times and durations as a user reads and writes them, one style for the daemon, the CLI and the
// results database: instants in ISO 8601 UTC to the second ("2026-12-02T03:04:05Z"), durations
// as Slurm prints them ([D-]HH:MM:SS) and wall-time limits as Slurm's --time takes them.
#include <chrono>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>

namespace mdem {

// ---- instants ---------------------------------------------------------------------------------

// "2026-12-02T03:04:05Z" for t (fractions of a second dropped).
std::string utc_text(std::chrono::system_clock::time_point t);
// utc_text of now.
std::string utc_now_text();
// A stored ISO 8601 UTC time in the shown style: fractions of a second dropped
// ("2026-12-02T03:04:05.123Z" -> "2026-12-02T03:04:05Z"); "" stays "", and text that is no such
// time is returned unchanged (never made up).
std::string shown_time(std::string_view iso);
// Seconds since the epoch of an ISO 8601 UTC time, with or without fractions; nullopt otherwise.
std::optional<double> epoch_seconds(std::string_view iso);

// ---- durations --------------------------------------------------------------------------------

// [D-]HH:MM:SS of a non-negative number of seconds (rounded down), "-" for a negative or
// non-finite one.
std::string duration_text(double seconds);

// The longest wall-time limit accepted anywhere: 30 days.
inline constexpr double kMaxTimeLimitS = 30.0 * 86400.0;

// The forms parse_time_limit accepts, for messages and help.
const char* time_limit_forms();

// A wall-time limit in seconds, written as Slurm's --time takes it: "MM" (minutes), "MM:SS",
// "HH:MM:SS", "D-HH", "D-HH:MM", "D-HH:MM:SS", or a number with a unit: "90s", "15m", "2h",
// "1.5d". Throws std::invalid_argument naming `who` (the flag or key), the value and the accepted
// forms for anything else: empty, garbage, zero, negative, non-finite, or above kMaxTimeLimitS.
double parse_time_limit(std::string_view text, std::string_view who);

}  // namespace mdem
