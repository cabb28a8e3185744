; One drink for one person: the robot fetches a cola from the kitchen fridge.
; Two routes lead from the living room to the kitchen (hallway or dining room).
(define (problem fetch-cola)
  (:domain fetch-drink)
  (:objects pr2 - robot
            living-room hallway dining-room kitchen - place
            kitchen-fridge - fridge
            top-shelf middle-shelf bottom-shelf - shelf
            cola - drink
            alice - person)
  (:init (at pr2 living-room) (hand-empty pr2)
         (connected living-room hallway) (connected hallway living-room)
         (connected hallway kitchen) (connected kitchen hallway)
         (connected living-room dining-room) (connected dining-room living-room)
         (connected dining-room kitchen) (connected kitchen dining-room)
         (clear living-room hallway) (clear hallway living-room)
         (clear hallway kitchen) (clear kitchen hallway)
         (clear living-room dining-room) (clear dining-room living-room)
         (clear dining-room kitchen) (clear kitchen dining-room)
         (fridge-in kitchen-fridge kitchen) (fridge-closed kitchen-fridge)
         (shelf-of top-shelf kitchen-fridge) (shelf-of middle-shelf kitchen-fridge) (shelf-of bottom-shelf kitchen-fridge)
         (on cola middle-shelf)
         (person-at alice living-room))
  (:goal (and (served alice cola) (fridge-closed kitchen-fridge))))
