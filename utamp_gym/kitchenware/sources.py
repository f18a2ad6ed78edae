"""Where the families' parameter ranges come from: product dimensions, trade and standards.

Each key is cited by a `Param.source` or a `Family.sources`; `docs/gen_kitchenware.py`
prints the table on docs/procedural.md. Densities of the materials are cited in
`utamp_gym.scene.materials`. Where a sampled range is narrower than what real products span
(`Param.real`), the reason is the robot's world: the slots of the table (40 x 30 cm), the
Panda's reach and its 8 cm hand; the wider range is still documented.
"""

from __future__ import annotations

from types import MappingProxyType

SOURCES: MappingProxyType[str, str] = MappingProxyType(
    {
        "mug": "Regular coffee mugs hold 8-12 fl oz (240-355 ml): 9-11.5 cm tall, 7.5-9 cm "
        "across the rim (hotchickalatte.com/how-big-is-a-regular-coffee-mug; "
        "myespressolab.com/what-is-the-standard-size-coffee-mug); ceramic walls 3-6 mm; "
        "C-handles leave a 2-3.5 cm finger opening",
        "tumbler": "Drinking glasses and tumblers: 6-8.5 cm across, 8.5-15 cm tall, soda-lime "
        "walls 2-4 mm on a 5-15 mm heavy base; PP/PET cups 1.5-3 mm; steel tumblers 0.6-1 mm",
        "dinnerware": "Dinner plates 25-28 cm, salad/dessert 18-22 cm, bread 15-17 cm "
        "(tableware.com, Dinnerware (Crockery)); cereal/soup bowls about 15-23 cm across and "
        "5-8 cm deep (lenox-china.net, Dinnerware comes with many pieces in mind)",
        "mixing-bowl": "Stainless mixing bowls 0.5-1.2 mm sheet; PP bowls 2-3.5 mm",
        "box": "Folding-carton food boxes (tea, crackers, pasta): 0.4-0.8 mm boxboard; tea "
        "boxes 15 x 6.5 x 8.5 cm, cracker boxes 20 x 7 x 16 cm; dry goods 150-600 kg/m^3 "
        "bulk density (tea 200-350, pasta 400-600)",
        "bottle": "750 ml wine bottle 30 cm tall, 7.5 cm across (cancanawards.com, 750 mL wine "
        "bottle); 500 ml oil bottles 6-7 cm across, 25-28 cm tall; bore 18.5-21 mm, neck "
        "finish 25-32 mm outside (mothersfinest.info, wine bottle standards)",
        "jar": "Mason jars: regular mouth 70 mm, wide mouth 86 mm; half-pint 7 cm across and "
        "9.5 cm tall, pint 8 cm and 13 cm (jobhop.co.uk, Mason Jar Dimensions and "
        "Specifications); jam 1300-1350 kg/m^3, dry goods 600-800",
        "skillet": "Frying pans are sized across the rim, 6-15 in (15-38 cm), most 20-30 cm "
        "(askvity.info, How are cast iron frying pans measured; homedutiesdone.com); cast-iron "
        "skillets weigh 4-5 lb at 8 in, 5-6 lb at 10 in (kitchensummary.com, How much does a "
        "cast iron skillet weigh); walls 2-3 mm (steel, aluminium) and 1.8-2.7 mm cast iron "
        "(stargazercastiron.com, ideal weight of a cast iron skillet)",
        "saucepan": "A 2-quart saucepan is 7-8 in (18-20 cm) across and 3.5-4 in (9-10 cm) deep "
        "(kitchenclue.com, How big is a 2 quart saucepan); saucepans hold 1-4 quarts and have "
        "one long handle (prudentreviews.com, Saucepan vs. pot)",
        "stock-pot": "Pots hold 6-20 quarts with a handle on each side; a 6-quart pot is 9-11 in "
        "across and 5-7 in tall (kitchencrafthubs.com, How big is a 6 qt pot; "
        "prudentreviews.com); small 1.5-3 l pots 14-20 cm",
        "cutting-board": "Cutting boards: small 8 x 10 to 10 x 12 in, medium 12 x 18 in "
        "(woodykitchenware.com, The ultimate guide to choosing a cutting board); 3/4-1.5 in "
        "thick (koppenhouse.com, Standard cutting board sizes); paddle boards add a 6-12 cm "
        "handle",
        "tray": "Serving trays 35-50 x 25-35 cm with 2-5 cm rims and handle bars or cut-outs; "
        "the catalogue's wooden tray (45 x 32 x 4.5 cm)",
        "sheet-pan": "Sheet pans: half size 12 7/8 x 17 3/4 in (33 x 45 cm), quarter size "
        "9 1/2 x 13 in (24 x 33 cm), sides of 1 in (3 cm), aluminium (Culinary Institute of "
        "America, Baking and Pastry, via app.ckbk.com, Baking pans); 0.8-1.2 mm sheet "
        "(lauvacs.com, Aluminum tray sizes)",
        "container": "Food storage containers (PP): 0.5-1.5 l, 12-22 cm long, 6-11 cm wide, "
        "5-11 cm tall, 1-2 mm walls",
        "utensil": "Wooden spatulas and turners: 28-35 cm long, blades 6-9 cm wide and 6-10 mm "
        "thick, handles 2-3 cm wide",
        "materials": "Densities: utamp_gym.scene.materials (USDA Wood Handbook, glass and "
        "ceramic data sheets, ASM Handbook)",
        "robot": "Sampled narrower than real products where the table (slots 40 x 30 cm), "
        "the Panda's reach or its 8 cm hand bound what the benchmark can hold",
    }
)

__all__ = ["SOURCES"]
