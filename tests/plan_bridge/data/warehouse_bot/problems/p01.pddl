(define (problem stow-two-crates)
  (:domain warehouse-bot)
  (:objects
    rb1 - agent
    dock inbound aisle-a racks - zone
    c7 c9 - crate)
  (:init
    (located rb1 dock)
    (gripper-empty rb1)
    (aisle dock inbound) (aisle inbound dock)
    (aisle inbound aisle-a) (aisle aisle-a inbound)
    (aisle aisle-a racks) (aisle racks aisle-a)
    (aisle dock aisle-a) (aisle aisle-a dock)
    (crate-in c7 inbound)
    (crate-in c9 inbound)
    (rack racks))
  (:goal (and (stowed c7) (stowed c9) (located rb1 dock))))
