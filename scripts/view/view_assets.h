#pragma once

#include <string_view>

// The page and its script, embedded in the binary at build time from scripts/view/page.html and
// scripts/view/view.js (nothing is fetched from elsewhere).
namespace mrslam::view {

std::string_view PageHtml();
std::string_view ViewJs();

}  // namespace mrslam::view
