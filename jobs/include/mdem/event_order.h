#pragma once
// Where a frame or snapshot lies in a job's run: by stage, then by step inside it. Steps alone do
// not order a job whose stages restart their clock (the tensile job after its pre-relaxation); a
// log from before stages were recorded (stage 0) orders by step. A resumed run (mdemd's, or
// `mdem run --resume`) skips what it reports at or before the last order already stored.

namespace mdem {

constexpr long event_order(int stage, long step) { return (static_cast<long>(stage) << 40) + step; }

}  // namespace mdem
