#include "features/feature_extractor.hpp"

#include "core/errors.hpp"
#include "features/orb_extractor.hpp"
#include "features/saft_extractor.hpp"

namespace builtscene {

DescriptorChoice parse_descriptor_choice(const std::string& name) {
  if (name == "orb") return DescriptorChoice::kOrb;
  if (name == "saft") return DescriptorChoice::kSaft;
  throw InputError("--descriptor: '" + name + "' is not one of orb, saft");
}

std::string to_string(DescriptorChoice choice) { return choice == DescriptorChoice::kOrb ? "orb" : "saft"; }

std::unique_ptr<FeatureExtractor> make_feature_extractor(DescriptorChoice choice, const OrbExtractorOptions& orb,
                                                         const std::filesystem::path& saft_weights) {
  if (choice == DescriptorChoice::kOrb) return std::make_unique<OrbExtractor>(orb);
  const auto weights = saft_weights.empty() ? SaftNetwork::default_weights_path() : saft_weights;
  return std::make_unique<SaftExtractor>(orb, SaftNetwork::load(weights));
}

}  // namespace builtscene
