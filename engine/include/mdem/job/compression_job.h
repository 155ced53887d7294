#pragma once
// The compression job (scenes.md compression): a packed, bonded particle of grains crushed
// between platens. Its force loop has grain bonds, linear contacts, platen contacts and, when
// asked for, dashpots: no CNT or vdW code.
//
// The platens are rigid (model.md §6: compare with the rigid-platen Hertz prefactor), centred on
// the z axis through the particle's centre, placed at the grains' z extremes (just touching, no
// force at the start), with the mass of the largest grain (it only enters the kinetic energy of
// their prescribed motion). Displacement h: their total approach, from their positions. Force:
// their reactions along z, compression positive. Slip (Eq. 40) is against the positions at the
// start of loading and, as Eq. 40 is written, also counts a rigid turn of the whole particle.
#include <memory>
#include <string_view>
#include <vector>

#include "mdem/force/bond/grain_bond.h"
#include "mdem/job/job.h"
#include "mdem/protocol/compression_protocol.h"
#include "mdem/scene/grain_packing.h"

namespace mdem {

class PackingStage;

// The platens, declared as element groups of the job's system: each on its own, and both.
inline constexpr std::string_view kTopPlaten = "compression.top_platen";
inline constexpr std::string_view kBottomPlaten = "compression.bottom_platen";
inline constexpr std::string_view kPlatens = "compression.platens";

struct CompressionJobSpec {
  PackingSpec particle;
  GrainBondParams bond;  // material copied from the particle's
  CompressionLoading loading;
  double viscous_ratio = 0.5;  // β of GrainDashpots; 0 = none (local damping: IntegratorSettings)
};

// Stages: "packing" (PackingStage, when the job packs its particle), then "compression" (the
// platens' CompressionProtocol, with a tracker of the peak force and the loading stiffness).
// The job's system, bonds and platens exist once the packing has finished (prepare_job, or
// run_job past the packing); before that, system() is the packing's.
class CompressionJob final : public Job {
 public:
  // Packs the particle (pack_grains, as the job's first stage), then bonds every touching pair,
  // places the platens touching the particle's top and bottom. Throws std::invalid_argument for
  // an impossible spec.
  CompressionJob(const CompressionJobSpec& spec, IntegratorSettings settings);
  // The same with a particle packed by the caller (e.g. carved out of a bulk packing); the spec's
  // particle gives the material, the largest grain radius and the platens' lateral size.
  CompressionJob(PackedParticle packed, const CompressionJobSpec& spec,
                 IntegratorSettings settings);
  CompressionJob(const CompressionJob&) = delete;
  CompressionJob& operator=(const CompressionJob&) = delete;
  ~CompressionJob() override;

  std::string_view kind() const override { return "compression"; }
  System& system() override;
  double duration() const override;
  // time, displacement h (nm), platen force (nN, mean of both, compression positive), bonds
  // intact / yielded / broken, fragments, max and mean slip (nm), then the energy columns.
  std::vector<std::string> columns() const override;
  std::vector<double> observe() override;
  // grains, bonds, porosity, rattlers, packing figures, peak force and its displacement, stiffness
  // of the first loading (least-squares F = k·h through the origin over h ≤ h_peak/2), force and
  // displacement at the end, residual height loss (initial minus current z extent of the grains),
  // bonds intact/yielded/broken, fragments, slip, energy-balance error, dt and critical dt.
  Summary summary() override;
  // Adds "slip_nm" (slip()) to snapshots.
  void decorate(Snapshot& s) const override;

  // Whether the particle is packed and the job's system built (the accessors below need it).
  bool built() const { return sys_ != nullptr; }
  // Slip vector magnitude per element (thesis Eq. 40): the mean over i's initial bonded
  // neighbours j of |x_ij − R·X_ij|, R the particle's best-fit rigid rotation since the start of
  // loading (Kabsch): frictionless platens let the particle turn freely, and turning is not
  // sliding. 0 for platens and unbonded grains.
  std::vector<double> slip() const;
  // Connected components of the intact bond graph over the grains bonded at the start (grains
  // that never had a bond, rattlers, are not fragments): 1 for an intact particle.
  long fragments() const;
  // The rotation R of slip().
  Mat3 rigid_rotation() const;
  // Current mean platen force (nN, compression positive): the z components of the platens'
  // reactions, contact force plus any dashpot force on them, (F_top − F_bottom)/2.
  double platen_force_nN() const;
  // Current total approach of the platens (nm), from their positions.
  double displacement() const;
  std::size_t top_platen() const { return top_; }
  std::size_t bottom_platen() const { return bottom_; }
  const CompressionProtocol& protocol() const { return *protocol_; }
  const PackedParticle& packing() const { return packed_; }
  const GrainBond& bonds() const;

 private:
  class Tracker;
  void stage_finished(std::size_t k) override;
  // Builds the system from the packed particle: platens, bonds, contacts, dashpots, references.
  void build(PackedParticle packed);
  void add_compression_stage();
  const System& sys() const;

  CompressionJobSpec spec_;
  IntegratorSettings settings_;
  PackingStage* packing_stage_ = nullptr;  // owned by the stage list; null when carved
  PackedParticle packed_;
  std::unique_ptr<System> sys_;
  GrainBond* bonds_ = nullptr;
  std::shared_ptr<CompressionProtocol> protocol_;
  std::shared_ptr<Tracker> tracker_;
  std::size_t top_ = 0, bottom_ = 0;
  static std::vector<EnergyTerm> energy_terms();
  double height() const;  // z extent of the grains (nm)

  std::size_t n_grains_ = 0, initial_bonds_ = 0;
  std::vector<Vec3> x0_;  // reference positions for the slip vector
  // Each grain's initial bonded neighbours (CSR).
  std::vector<std::uint32_t> slip_offsets_, slip_partners_;
  double z_top0_ = 0, z_bottom0_ = 0, height0_ = 0;
};

}  // namespace mdem
