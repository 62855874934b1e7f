//! Every controller's BIOS code table travels whole (TROLGetCodes): no name or meaning is
//! longer than the reply carries, so no host reads a meaning cut off mid-word (issue 42:
//! the C500's BIOS_UNSUPPORTED arrived as "... the C500 keeps them itsel").

use trol_proto::application::code::too_long_for_the_wire;

#[test]
fn every_controller_s_codes_fit_the_wire() {
    for (kind, table) in [
        ("simulated A465", trol_sim::SIM_CODES),
        ("C500 over RAPL-II", trol_rapl::RAPL_CODES),
        ("MARS 8", trol_mars::MARS_CODES),
    ] {
        let long = too_long_for_the_wire(table);
        assert!(long.is_empty(), "{kind}:\n{}", long.join("\n"));
    }
}
