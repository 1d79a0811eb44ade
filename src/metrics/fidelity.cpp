// Fidelity against ground truth: differing pixels, PSNR, visible objects missed, the pixel
// error (issue 14, src/metrics/pixel_error.cpp), and the stratified-rendering thesis's
// difference images (difference + 128).
#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <unordered_map>
#include <unordered_set>

#include <nlohmann/json.hpp>

#include "cellwalk/core/atomic_file.hpp"
#include "cellwalk/core/error.hpp"
#include "cellwalk/metrics/fidelity.hpp"
#include "cellwalk/runtime/walk.hpp"

namespace cellwalk {

FidelityFrame compare_images(const Image& truth, const IdImage& truth_ids, const Image& test,
                             const IdImage& test_ids, Image* difference) {
  if (truth.width != test.width || truth.height != test.height || truth_ids.ids.size() != test_ids.ids.size())
    fail("compare", "images of different sizes");
  FidelityFrame f;
  const size_t pixels = static_cast<size_t>(truth.width) * truth.height;
  if (difference) {
    difference->width = truth.width;
    difference->height = truth.height;
    difference->rgba.assign(pixels * 4, 255);
  }
  uint64_t differing = 0;
  double squared = 0.0;
  for (size_t p = 0; p < pixels; ++p) {
    bool differs = false;
    for (int c = 0; c < 3; ++c) {
      const int d = int(test.rgba[4 * p + c]) - int(truth.rgba[4 * p + c]);
      differs |= d != 0;
      squared += double(d) * d;
      if (difference) difference->rgba[4 * p + c] = static_cast<uint8_t>(std::clamp(128 + d, 0, 255));
    }
    differing += differs ? 1 : 0;
  }
  f.differing_fraction = pixels ? double(differing) / double(pixels) : 0.0;
  const double mse = pixels ? squared / (3.0 * double(pixels)) : 0.0;
  f.psnr_db = mse > 0 ? 10.0 * std::log10(255.0 * 255.0 / mse) : std::numeric_limits<double>::infinity();
  std::unordered_map<uint32_t, uint64_t> truth_pixels;  // per id shown, its pixels
  for (uint32_t id : truth_ids.ids) ++truth_pixels[id];
  truth_pixels.erase(kBackgroundId);
  std::unordered_set<uint32_t> seen_test(test_ids.ids.begin(), test_ids.ids.end());
  f.visible_objects = truth_pixels.size();
  for (const auto& [id, count] : truth_pixels)
    if (!seen_test.count(id)) {
      f.missed_ids.push_back(id);
      f.largest_missed_pixels = std::max(f.largest_missed_pixels, count);
    }
  std::sort(f.missed_ids.begin(), f.missed_ids.end());
  f.missed_objects = f.missed_ids.size();
  f.width = truth.width;
  f.test_to_truth = pixel_error(test_ids, truth_ids);
  f.truth_to_test = pixel_error(truth_ids, test_ids);
  return f;
}

namespace {

// How many of `pixel_ids` belong to items of `drawn`.
uint64_t count_drawn(const std::vector<uint32_t>& pixel_ids, const std::vector<DrawItem>& drawn) {
  std::unordered_set<uint32_t> ids;
  for (const DrawItem& item : drawn) ids.insert(pixel_id(item));
  return uint64_t(std::count_if(pixel_ids.begin(), pixel_ids.end(), [&](uint32_t id) { return ids.count(id) > 0; }));
}

}  // namespace

std::vector<std::vector<FidelityFrame>> compare_side_by_side(const CameraPath& path, const Camera& lens,
                                                         std::span<Strategy* const> strategies, Strategy& truth,
                                                         Renderer& renderer, const CompareOptions& options,
                                                         const ProgressFn& progress) {
  if (options.every < 1) fail("compare", "--every must be at least 1");
  std::vector<std::vector<FidelityFrame>> frames(strategies.size());
  Camera camera = lens;
  int images = 0;
  for (size_t i = 0; i < path.frames.size(); i += static_cast<size_t>(options.every)) {
    apply(path.frames[i], camera);
    render_frame(truth, renderer, camera);
    const Image truth_color = renderer.read_color();
    const IdImage truth_ids = renderer.read_ids();
    const bool write_images = !options.image_dir.empty() && images < options.max_images;
    const std::string stem = options.image_dir + "/frame" + std::to_string(i);
    if (write_images) write_png(truth_color, stem + "-truth.png");
    for (size_t k = 0; k < strategies.size(); ++k) {
      std::vector<DrawItem> drawn;
      render_frame(*strategies[k], renderer, camera, path.frames[i].time, &drawn);
      const Image test_color = renderer.read_color();
      Image diff;
      FidelityFrame f = compare_images(truth_color, truth_ids, test_color, renderer.read_ids(), &diff);
      f.missed_drawn = count_drawn(f.missed_ids, drawn);
      f.frame = static_cast<int>(i);
      frames[k].push_back(std::move(f));
      if (write_images) {
        const std::string label =
            strategies.size() == 1 && !options.label.empty() ? options.label : strategies[k]->name();
        write_png(test_color, stem + "-" + label + ".png");
        write_png(diff, stem + "-" + label + "-diff.png");
      }
    }
    images += write_images ? 1 : 0;
    if (progress) progress(i + 1, path.frames.size());
  }
  return frames;
}

std::vector<FidelityFrame> compare(const CameraPath& path, const Camera& lens, Strategy& strategy,
                                   Strategy& truth, Renderer& renderer,
                                   const CompareOptions& options, const ProgressFn& progress) {
  Strategy* const one[] = {&strategy};
  return std::move(compare_side_by_side(path, lens, one, truth, renderer, options, progress).front());
}

std::vector<FidelityFrame> compare_captured(const CameraPath& path, const Camera& lens, std::span<const CapturedFrame> captured,
                                            Strategy& truth, Renderer& renderer, const CompareOptions& options,
                                            const ProgressFn& progress) {
  std::vector<FidelityFrame> frames;
  Camera camera = lens;
  int images = 0;
  for (const CapturedFrame& c : captured) {
    const std::string name = "captured frame " + std::to_string(c.frame);
    if (c.frame < 0 || size_t(c.frame) >= path.frames.size())
      fail(name, "the path has " + std::to_string(path.frames.size()) + " frames; capture the same path");
    const RenderSettings& s = renderer.settings();
    if (c.color.width != s.width || c.color.height != s.height || c.ids.width != s.width || c.ids.height != s.height)
      fail(name, "its images are " + std::to_string(c.color.width) + " × " + std::to_string(c.color.height) + ", not " +
                     std::to_string(s.width) + " × " + std::to_string(s.height));
    apply(path.frames[size_t(c.frame)], camera);
    render_frame(truth, renderer, camera);
    const Image truth_color = renderer.read_color();
    Image diff;
    FidelityFrame f = compare_images(truth_color, renderer.read_ids(), c.color, c.ids, &diff);
    f.frame = c.frame;
    frames.push_back(std::move(f));
    if (!options.image_dir.empty() && images < options.max_images) {
      const std::string stem = options.image_dir + "/frame" + std::to_string(c.frame);
      const std::string label = options.label.empty() ? "captured" : options.label;
      write_png(truth_color, stem + "-truth.png");
      write_png(c.color, stem + "-" + label + ".png");
      write_png(diff, stem + "-" + label + "-diff.png");
      ++images;
    }
    if (progress) progress(frames.size(), captured.size());
  }
  return frames;
}

FidelitySummary summarize(const std::vector<FidelityFrame>& frames) {
  FidelitySummary s;
  s.frames = frames.size();
  // PSNR of the mean squared error over every compared frame: identical frames count as
  // error 0 rather than being left out of an average of decibels.
  constexpr double kPeak = 255.0 * 255.0;
  double mse_sum = 0.0;
  for (const FidelityFrame& f : frames) {
    s.mean_differing_fraction += f.differing_fraction;
    s.max_differing_fraction = std::max(s.max_differing_fraction, f.differing_fraction);
    s.visible_objects += f.visible_objects;
    s.missed_objects += f.missed_objects;
    s.missed_drawn += f.missed_drawn;
    s.largest_missed_pixels = std::max(s.largest_missed_pixels, f.largest_missed_pixels);
    if (std::isfinite(f.psnr_db)) mse_sum += kPeak / std::pow(10.0, f.psnr_db / 10.0);
    s.max_pixel_error_px = std::max(s.max_pixel_error_px, f.pixel_error_max_px());
    s.max_pixel_error_p999_px = std::max(s.max_pixel_error_p999_px, f.pixel_error_p999_px());
    s.pixel_error_over_1px_fraction += f.pixel_error_max_px() > 1.0 ? 1 : 0;
    s.pixel_error_p999_over_1px_fraction += f.pixel_error_p999_px() > 1.0 ? 1 : 0;
    s.unmatched_test_pixels += f.test_to_truth.unmatched;
    s.unmatched_truth_pixels += f.truth_to_test.unmatched;
  }
  if (!frames.empty()) {
    s.mean_differing_fraction /= double(frames.size());
    s.pixel_error_over_1px_fraction /= double(frames.size());
    s.pixel_error_p999_over_1px_fraction /= double(frames.size());
  }
  const double mean_mse = frames.empty() ? 0.0 : mse_sum / double(frames.size());
  s.mean_psnr_db = mean_mse > 0 ? 10.0 * std::log10(kPeak / mean_mse) : std::numeric_limits<double>::infinity();
  s.recall = s.visible_objects ? 1.0 - double(s.missed_objects) / double(s.visible_objects) : 1.0;
  return s;
}

void write_fidelity_csv(const std::vector<FidelityFrame>& frames, const std::string& file) {
  std::ostringstream out;
  out << "frame,differing_fraction,psnr_db,visible_objects,missed_objects,missed_drawn,largest_missed_pixels,"
         "test_to_truth_max_px,test_to_truth_p999_px,test_to_truth_unmatched,"
         "truth_to_test_max_px,truth_to_test_p999_px,truth_to_test_unmatched,"
         "worst_x,worst_y,missed_object_ids\n";
  out.precision(6);
  auto write_pixel_error = [&out](const PixelErrorStats& e) {
    out << ',' << e.max_px << ',' << e.p999_px << ',' << e.unmatched;
  };
  for (const FidelityFrame& f : frames) {
    out << f.frame << ',' << f.differing_fraction << ',' << f.psnr_db << ',' << f.visible_objects << ','
        << f.missed_objects << ',' << f.missed_drawn << ',' << f.largest_missed_pixels;
    write_pixel_error(f.test_to_truth);
    write_pixel_error(f.truth_to_test);
    // Where the frame's pixel error is largest (the worse direction), and which objects it
    // missed: what to look at in the frame's images.
    const PixelErrorStats& worse =
        f.test_to_truth.max_px >= f.truth_to_test.max_px ? f.test_to_truth : f.truth_to_test;
    if (worse.worst_pixel >= 0 && f.width > 0)
      out << ',' << worse.worst_pixel % f.width << ',' << worse.worst_pixel / f.width;
    else
      out << ",,";
    out << ',';
    // Truth draws objects only, whose pixel id is the object's id + 1.
    for (size_t i = 0; i < f.missed_ids.size(); ++i) out << (i ? " " : "") << f.missed_ids[i] - 1;
    out << '\n';
  }
  write_file_atomically(file, out.str());
}

std::string to_json(const FidelitySummary& s) {
  // JSON has no infinity: identical images report psnr_db as null.
  auto number = [](double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr); };
  nlohmann::ordered_json j = {{"frames", s.frames},
                              {"mean_differing_fraction", s.mean_differing_fraction},
                              {"max_differing_fraction", s.max_differing_fraction},
                              {"mean_psnr_db", number(s.mean_psnr_db)},
                              {"visible_objects", s.visible_objects},
                              {"missed_objects", s.missed_objects},
                              {"missed_drawn", s.missed_drawn},
                              {"largest_missed_pixels", s.largest_missed_pixels},
                              {"recall", s.recall},
                              {"pixel_error",
                               {{"max_px", s.max_pixel_error_px},
                                {"p999_px", s.max_pixel_error_p999_px},
                                {"frames_max_over_1px", s.pixel_error_over_1px_fraction},
                                {"frames_p999_over_1px", s.pixel_error_p999_over_1px_fraction},
                                {"unmatched_test_pixels", s.unmatched_test_pixels},
                                {"unmatched_truth_pixels", s.unmatched_truth_pixels}}}};
  return j.dump(2);
}

}  // namespace cellwalk
